#!/usr/bin/env python3
"""Hand-eye accuracy: saras_calibration's robust solver vs each OpenCV method on the same data.

Scenario A = OpenCV's own test (test_calibration_hand_eye.cpp, eye-in-hand): 10 poses, noise
camera 0.002 rad / 5 mm, robot 0.001 rad / 1 mm (added to rotation vectors and translations),
clean and with one bad marker pose in ten (10-40 deg, 2-10 cm gross error).
Scenario B = endoscope scale (issue 8): 20 samples, 0.1 deg / 0.5 mm RMS noise, 15 % outliers.
Errors vs the generating transform: rotation angle [deg], translation [mm]; mean over trials.
"""
import argparse
import time

import numpy as np

from saras_calibration.hand_eye import HandEyeError, OPENCV_METHODS, solve_hand_eye
from saras_calibration.synthetic import ecm_hand_eye_dataset, opencv_hand_eye_dataset
from saras_common.transforms import inverse, rotation_angle_deg

METHODS = ['robust'] + list(OPENCV_METHODS)


def run(make, trials):
    err = {m: [] for m in METHODS}
    fails = {m: 0 for m in METHODS}
    secs = {m: 0.0 for m in METHODS}
    for k in range(trials):
        ee, cm, X, _ = make(np.random.default_rng(1000 + k))
        for m in METHODS:
            t0 = time.perf_counter()
            try:
                T = solve_hand_eye(ee, cm, method=m).transform
            except HandEyeError:
                fails[m] += 1
                continue
            finally:
                secs[m] += time.perf_counter() - t0
            E = inverse(X) @ T
            err[m].append((rotation_angle_deg(E[:3, :3]), 1e3 * np.linalg.norm(T[:3, 3] - X[:3, 3])))
    return {m: (np.mean(err[m], axis=0) if err[m] else (np.nan, np.nan), fails[m], 1e3 * secs[m] / trials)
            for m in METHODS}


def table(title, clean, bad, bad_label):
    print('\n' + title)
    print('| method | clean rot [deg] | clean trans [mm] | %s rot [deg] | %s trans [mm] | worse x (rot, trans) | ms/solve |'
          % (bad_label, bad_label))
    print('|---|---|---|---|---|---|---|')
    ref = clean['robust'][0]
    for m in METHODS:
        (cr, ct), cf, ms = clean[m]
        (br, bt), bf, _ = bad[m]
        note = '' if not (cf or bf) else ' (failed: %d clean, %d bad)' % (cf, bf)
        print('| %s%s | %.4f | %.3f | %.4f | %.3f | %.1f, %.1f | %.1f |'
              % (m, note, cr, ct, br, bt, br / cr, bt / ct, ms))
    best = min(clean[m][0][0] for m in OPENCV_METHODS)
    best_t = min(clean[m][0][1] for m in OPENCV_METHODS)
    print('targets: clean robust <= best OpenCV: rot %.4f <= %.4f (%s), trans %.3f <= %.3f (%s); '
          'with outliers within 1.5x of clean robust: rot %.2fx, trans %.2fx (%s)'
          % (ref[0], best, 'OK' if ref[0] <= best else 'MISSED', ref[1], best_t, 'OK' if ref[1] <= best_t else 'MISSED',
             bad['robust'][0][0] / ref[0], bad['robust'][0][1] / ref[1],
             'OK' if max(bad['robust'][0][0] / ref[0], bad['robust'][0][1] / ref[1]) <= 1.5 else 'MISSED'))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('--trials', type=int, default=100)
    a = ap.parse_args()
    n = a.trials
    clean = run(lambda r: opencv_hand_eye_dataset(r, 10), n)
    bad = run(lambda r: opencv_hand_eye_dataset(r, 10, n_outliers=1), n)
    table('A. OpenCV test scenario, 10 poses, %d trials (bad = 1 bad pose in 10)' % n, clean, bad, 'bad')
    clean = run(lambda r: ecm_hand_eye_dataset(r, 20), n)
    bad = run(lambda r: ecm_hand_eye_dataset(r, 20, outlier_fraction=0.15), n)
    table('B. Endoscope scale, 20 samples, 0.1 deg / 0.5 mm, %d trials (bad = 15 %% outliers)' % n, clean, bad, '15%')


if __name__ == '__main__':
    main()
