#!/usr/bin/env python3
"""Stereo calibration on real images: corner methods, then this package vs OpenCV vs mrcal.

Data: OpenCV's stereo checkerboard set (Debian ``opencv-doc``, 13 pairs, 640x480, 9x6 inner
corners). Every error is in pixels and computed by the same code
(:mod:`saras_calibration.accuracy`): per-camera reprojection RMS with a free board pose per view,
leave-one-out hold-out (calibrate on 12 pairs, fit the board pose of the 13th: per camera, and
left pose -> right image through R, T: "transfer"), epipolar RMS after rectification.

Table 1 (corner methods): each method's corners through the same solver.
Table 2 (pipelines): this package (``calibrate_stereo``: corners, view selection, solve,
hold-out, uncertainties), OpenCV's sample pipeline (``cornerSubPix`` 11x11, ``calibrateCamera``,
``stereoCalibrate``), and mrcal (``mrcal-calibrate-cameras``, LENSMODEL_OPENCV5, on this
package's corners, flat board so that the model is the same; mrcal's projection uncertainty at
the image centre in the last column).
"""
import argparse
import glob
import os
import shutil
import subprocess
import tempfile
import time

import cv2
import numpy as np

from saras_calibration import accuracy
from saras_calibration.corners import available_methods, detect_corners
from saras_calibration.stereo import calibrate_stereo

BOARD, SQUARE, SIZE = (9, 6), 0.025, (640, 480)


def load(data):
    files = [sorted(glob.glob(os.path.join(data, s + '[0-9]*.jpg'))) for s in ('left', 'right')]
    return files, [[cv2.imread(f, cv2.IMREAD_GRAYSCALE) for f in fs] for fs in files]


def evaluate(left, right, sol_fn):
    """Metrics of a solver ``sol_fn(left, right) -> StereoSolution`` on these corners."""
    obj = accuracy.object_points(BOARD, SQUARE)
    sol = sol_fn(left, right)
    rms = [np.sqrt(np.mean(np.concatenate(e))) for e in accuracy._heldout_errors(obj, sol, left, right)[:2]]
    el, er, et = [], [], []
    for i in range(len(left)):
        s = sol_fn([c for j, c in enumerate(left) if j != i], [c for j, c in enumerate(right) if j != i])
        a, b, c = accuracy._heldout_errors(obj, s, [left[i]], [right[i]])
        el, er, et = el + a, er + b, et + c
    ho = [np.sqrt(np.mean(np.concatenate(e))) for e in (el, er, et)]
    return {'rms': rms, 'holdout': ho, 'epipolar': accuracy.epipolar_rms(sol, left, right, SIZE),
            'baseline_mm': sol.baseline * 1e3, 'sol': sol}


def opencv_solver(left, right):
    return accuracy.solve_stereo(accuracy.object_points(BOARD, SQUARE), left, right, SIZE, extended=False)


def corner_table(images):
    print('\n## Corner methods (same solver: calibrateCamera + stereoCalibrate)\n')
    print('| corners | pairs | RMS L / R [px] | hold-out L / R [px] | transfer [px] | epipolar [px] '
          '| baseline [mm] | detection [ms/image] |')
    print('|---|---|---|---|---|---|---|---|')
    for m in available_methods():
        t = time.perf_counter()
        cs = [[detect_corners(g, BOARD, m) for g in imgs] for imgs in images]
        dt = (time.perf_counter() - t) / (2 * len(images[0])) * 1e3
        keep = [i for i in range(len(cs[0])) if cs[0][i] is not None and cs[1][i] is not None]
        r = evaluate([cs[0][i] for i in keep], [cs[1][i] for i in keep], opencv_solver)
        print('| %s | %d | %.3f / %.3f | %.3f / %.3f | %.3f | %.3f | %.2f | %.1f |'
              % (m, len(keep), r['rms'][0], r['rms'][1], r['holdout'][0], r['holdout'][1], r['holdout'][2],
                 r['epipolar'], r['baseline_mm'], dt))


def _mrcal_run(files, corners, outdir):
    """mrcal-calibrate-cameras on given corners; images linked as <outdir>/<side>-NN.jpg."""
    cache = os.path.join(outdir, 'corners.vnl')
    with open(cache, 'w') as f:
        f.write('# filename x y level\n')
        for side, fs, cs in zip(('left', 'right'), files, corners):
            for k, (fn, c) in enumerate(zip(fs, cs)):
                link = os.path.join(outdir, '%s-%02d.jpg' % (side, k))
                os.symlink(os.path.abspath(fn), link)
                f.writelines('%s %.4f %.4f 0\n' % (link, x, y) for x, y in c.reshape(-1, 2))
    cmd = ['mrcal-calibrate-cameras', '--corners-cache', cache, '--lensmodel', 'LENSMODEL_OPENCV5', '--focal', '500',
           '--object-spacing', str(SQUARE), '--object-width-n', str(BOARD[0]), '--object-height-n', str(BOARD[1]),
           '--skip-calobject-warp-solve', '--outdir', outdir,
           os.path.join(outdir, 'left-*.jpg'), os.path.join(outdir, 'right-*.jpg')]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    import mrcal
    return [mrcal.cameramodel(os.path.join(outdir, 'camera-%d.cameramodel' % i)) for i in (0, 1)]


def mrcal_solver(files, all_left):
    """Solver ``(left, right) -> StereoSolution`` from mrcal's models (camera 0 is the reference);
    the views are found back among ``all_left`` to pick their image files."""
    import mrcal
    index = {id(c): i for i, c in enumerate(all_left)}

    def solve(left, right):
        sel = [index[id(c)] for c in left]
        tmp = tempfile.mkdtemp(prefix='saras_mrcal_')
        try:
            m = _mrcal_run([[files[0][i] for i in sel], [files[1][i] for i in sel]], [left, right], tmp)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        K, D = [], []
        for model in m:
            p = model.intrinsics()[1]
            K.append(np.array([[p[0], 0, p[2]], [0, p[1], p[3]], [0, 0, 1.0]]))
            D.append(np.array(p[4:9]))
        Rt = mrcal.Rt_from_rt(m[1].extrinsics_rt_fromref())
        sol = accuracy.StereoSolution(K[0], D[0], K[1], D[1], Rt[:3], Rt[3], (0.0, 0.0), 0.0)
        sol.models = m
        return sol
    return solve


def pipeline_table(files, images):
    print('\n## Pipelines on the same images\n')
    print('| pipeline | pairs | RMS L / R [px] | hold-out L / R [px] | transfer [px] | epipolar [px] '
          '| baseline [mm] | time [s] | uncertainty |')
    print('|---|---|---|---|---|---|---|---|---|')
    t = time.perf_counter()
    res = calibrate_stereo(images[0], images[1], BOARD, SQUARE)
    dt = time.perf_counter() - t
    t = time.perf_counter()
    calibrate_stereo(images[0], images[1], BOARD, SQUARE, folds=0)
    dt0 = time.perf_counter() - t
    ho = res.holdout
    print('| saras_calibration | %d | %.3f / %.3f | %.3f / %.3f | %.3f | %.3f | %.2f | %.1f (%.1f without hold-out) | '
          'fx %.2f px, baseline %.3f mm (1 sigma) |'
          % (res.n_views, res.reprojection_rms_px[0], res.reprojection_rms_px[1], ho['left_rms_px'],
             ho['right_rms_px'], ho['transfer_rms_px'], res.epipolar_rms_px, res.baseline_m * 1e3, dt, dt0,
             res.left['std']['fx'], ho['baseline_std'] * 1e3))
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    t = time.perf_counter()
    cs = [[cv2.cornerSubPix(g, cv2.findChessboardCorners(g, BOARD, None)[1], (11, 11), (-1, -1), crit)
           for g in imgs] for imgs in images]
    opencv_solver(cs[0], cs[1])
    dt = time.perf_counter() - t
    r = evaluate(cs[0], cs[1], opencv_solver)
    print('| OpenCV sample (cornerSubPix 11x11) | %d | %.3f / %.3f | %.3f / %.3f | %.3f | %.3f | %.2f | %.1f | - |'
          % (len(cs[0]), r['rms'][0], r['rms'][1], r['holdout'][0], r['holdout'][1], r['holdout'][2],
             r['epipolar'], r['baseline_mm'], dt))
    if shutil.which('mrcal-calibrate-cameras') is None:
        print('| mrcal | not installed (apt-get install mrcal python3-mrcal) |')
        return
    cs = [[detect_corners(g, BOARD) for g in imgs] for imgs in images]
    solve = mrcal_solver(files, cs[0])
    t = time.perf_counter()
    sol = solve(cs[0], cs[1])
    dt = time.perf_counter() - t
    r = evaluate(cs[0], cs[1], solve)
    import mrcal
    unc = mrcal.projection_uncertainty(mrcal.unproject(np.array([SIZE[0] / 2, SIZE[1] / 2]), *sol.models[0].intrinsics())
                                       * 1.0, model=sol.models[0], atinfinity=True)
    print('| mrcal 2.2 (OPENCV5, flat board, this package\'s corners) | %d | %.3f / %.3f | %.3f / %.3f | %.3f | %.3f '
          '| %.2f | %.1f | projection at centre %.3f px (1 sigma) |'
          % (len(cs[0]), r['rms'][0], r['rms'][1], r['holdout'][0], r['holdout'][1], r['holdout'][2],
             r['epipolar'], r['baseline_mm'], dt, np.sqrt(np.max(np.linalg.eigvalsh(unc)))))


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--data', default='/usr/share/doc/opencv-doc/examples/data')
    args = p.parse_args()
    files, images = load(args.data)
    if len(files[0]) == 0:
        print('no images in %s: apt-get install opencv-doc' % args.data)
        return 1
    print('# Stereo calibration, %d real pairs from %s (%dx%d board corners)' % (len(files[0]), args.data, *BOARD))
    corner_table(images)
    pipeline_table(files, images)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
