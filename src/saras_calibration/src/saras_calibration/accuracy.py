"""Stereo solve and its accuracy: reprojection, epipolar and hold-out errors, uncertainties (ROS-free).

The solve is camera_calibration's: Zhang intrinsics per camera with the plumb-bob model
(``cv2.calibrateCamera``, no flags), then ``cv2.stereoCalibrate`` with the intrinsics fixed.
Two differences: the intrinsics come from ``cv2.calibrateCameraExtended`` (same solution, plus
the standard deviations of fx, fy, cx, cy, k1, k2, p1, p2, k3), and ``stereoCalibrate`` runs to
convergence (camera_calibration stops it after one iteration).

Hold-out (:func:`cross_validate`): the views are split into ``folds`` groups; each group is
left out in turn, the rest is calibrated, and the left-out views are measured with that
calibration: per camera the reprojection RMS after fitting only the board pose (``solvePnP``),
and the stereo transfer RMS (board pose from the left image, projected into the right one
through R, T: every calibrated parameter takes part). The spread of the fold solutions gives a
grouped-jackknife standard deviation of the baseline and of T.
"""
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ['DIST_NAMES', 'StereoSolution', 'object_points', 'solve_stereo', 'epipolar_rms', 'cross_validate']

DIST_NAMES = ('k1', 'k2', 'p1', 'p2', 'k3')
_INTR_NAMES = ('fx', 'fy', 'cx', 'cy') + DIST_NAMES
_STEREO_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-10)


@dataclass
class StereoSolution:
    """``Kl, Dl, Kr, Dr`` intrinsics [px]; ``R, T``: p_right = R p_left + T (T in board units);
    ``rms``: (left, right) calibrateCamera RMS [px]; ``stereo_rms`` [px]; ``std``: per camera
    dict of standard deviations (None unless extended)."""
    Kl: np.ndarray
    Dl: np.ndarray
    Kr: np.ndarray
    Dr: np.ndarray
    R: np.ndarray
    T: np.ndarray
    rms: tuple
    stereo_rms: float
    std: tuple = (None, None)

    @property
    def baseline(self):
        return float(np.linalg.norm(self.T))


def object_points(board, square):
    """Board corners (x along a row, y down the rows, z = 0), float32 ``(N, 3)``, in square units."""
    cols, rows = board
    obj = np.zeros((cols * rows, 3), np.float32)
    obj[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * float(square)
    return obj


def _mono(obj, corners, size, extended):
    objs = [obj] * len(corners)
    if not extended:
        rms, K, D, _, _ = cv2.calibrateCamera(objs, corners, size, None, None)
        return rms, K, D.ravel()[:5], None
    rms, K, D, _, _, std, _, _ = cv2.calibrateCameraExtended(objs, corners, size, None, None)
    std = std.ravel()
    return rms, K, D.ravel()[:5], {n: float(std[i]) for i, n in enumerate(_INTR_NAMES)}


def solve_stereo(obj, left, right, size, extended=True):
    """Calibrate both cameras and the pair from corner lists (one ``(N, 1, 2)`` array per view)."""
    rl, Kl, Dl, sl = _mono(obj, left, size, extended)
    rr, Kr, Dr, sr = _mono(obj, right, size, extended)
    rs, _, _, _, _, R, T, _, _ = cv2.stereoCalibrate(
        [obj] * len(left), left, right, Kl, Dl, Kr, Dr, size, flags=cv2.CALIB_FIX_INTRINSIC,
        criteria=_STEREO_CRITERIA)
    return StereoSolution(Kl, Dl, Kr, Dr, R, T.ravel(), (float(rl), float(rr)), float(rs), (sl, sr))


def epipolar_rms(sol, left, right, size):
    """RMS [px] of the vertical disparity of matching corners after rectification (alpha 0)."""
    R1, R2, P1, P2 = cv2.stereoRectify(sol.Kl, sol.Dl, sol.Kr, sol.Dr, size, sol.R, sol.T, alpha=0)[:4]
    sq = []
    for a, b in zip(left, right):
        ua = cv2.undistortPoints(a, sol.Kl, sol.Dl, R=R1, P=P1)
        ub = cv2.undistortPoints(b, sol.Kr, sol.Dr, R=R2, P=P2)
        sq.append((ua[:, 0, 1] - ub[:, 0, 1]) ** 2)
    return float(np.sqrt(np.mean(np.concatenate(sq))))


def _heldout_errors(obj, sol, left, right):
    """Squared errors of held-out views: left PnP, right PnP, left -> right transfer."""
    el, er, et = [], [], []
    for a, b in zip(left, right):
        _, rl, tl = cv2.solvePnP(obj, a, sol.Kl, sol.Dl)
        _, rr, tr = cv2.solvePnP(obj, b, sol.Kr, sol.Dr)
        el.append(np.sum((cv2.projectPoints(obj, rl, tl, sol.Kl, sol.Dl)[0] - a) ** 2, axis=2).ravel())
        er.append(np.sum((cv2.projectPoints(obj, rr, tr, sol.Kr, sol.Dr)[0] - b) ** 2, axis=2).ravel())
        Rb = sol.R @ cv2.Rodrigues(rl)[0]
        tb = sol.R @ tl.ravel() + sol.T
        pt = cv2.projectPoints(obj, cv2.Rodrigues(Rb)[0], tb, sol.Kr, sol.Dr)[0]
        et.append(np.sum((pt - b) ** 2, axis=2).ravel())
    return el, er, et


def cross_validate(obj, left, right, size, folds=13):
    """Hold-out errors and jackknife spread; ``folds`` is capped at the number of views
    (``folds = n`` is leave-one-out). Returns a dict (pixels; ``baseline_std``, ``T_std`` in
    the units of ``obj``)."""
    n = len(left)
    k = int(min(max(folds, 2), n))
    groups = np.array_split(np.arange(n), k)
    el, er, et, base, Ts = [], [], [], [], []
    for g in groups:
        train = [i for i in range(n) if i not in set(g)]
        sol = solve_stereo(obj, [left[i] for i in train], [right[i] for i in train], size, extended=False)
        a, b, c = _heldout_errors(obj, sol, [left[i] for i in g], [right[i] for i in g])
        el += a
        er += b
        et += c
        base.append(sol.baseline)
        Ts.append(sol.T)

    def rms(x):
        return float(np.sqrt(np.mean(np.concatenate(x))))

    jk = (k - 1) / k
    Ts = np.array(Ts)
    return {'folds': k, 'left_rms_px': rms(el), 'right_rms_px': rms(er), 'transfer_rms_px': rms(et),
            'baseline_std': float(np.sqrt(jk * np.sum((np.array(base) - np.mean(base)) ** 2))),
            'T_std': np.sqrt(jk * np.sum((Ts - Ts.mean(axis=0)) ** 2, axis=0))}
