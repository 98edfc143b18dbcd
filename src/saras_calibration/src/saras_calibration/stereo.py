"""Headless stereo calibration of the endoscope in ROS ``camera_calibration``'s workflow.

``camera_calibration``'s ``StereoCalibrator`` keeps the views' description, rectifies
(``cv2.stereoRectify``, alpha 0) and writes the camera_info YAML of each camera
(``camera_calibration_parsers`` format, the one ``camera_info_manager`` and the endoscope driver
load). This module feeds it image pairs without a GUI and replaces three of its steps with
measured better ones:

* corners: :mod:`saras_calibration.corners` (``scaled_subpix`` by default: 2.3x lower
  reprojection RMS than camera_calibration's refinement on OpenCV's real stereo images);
* view selection and the "good enough" test: :mod:`saras_calibration.views` (keeps every view
  of a standard set, says what is missing);
* the solve: :mod:`saras_calibration.accuracy` (standard deviations, a converged
  ``stereoCalibrate``), plus hold-out errors and the jackknife spread of the baseline.
"""
from dataclasses import dataclass, field

import cv2
import numpy as np
from camera_calibration.calibrator import ChessboardInfo, Patterns, StereoCalibrator

from saras_calibration import accuracy, views
from saras_calibration.corners import available_methods, detect_corners

__all__ = ['StereoCalibrationError', 'StereoSampleCollector', 'StereoCalibrationResult', 'calibrate_stereo',
           'parse_board_size', 'DEFAULT_MIN_VIEWS']

#: Fewest views calibrated from by default (OpenCV's standard stereo set has 13).
DEFAULT_MIN_VIEWS = 10


class StereoCalibrationError(RuntimeError):
    """Calibration impossible (no board found, too few views or too little coverage, bad images)."""


def parse_board_size(text):
    """``"8x6"`` -> (8, 6) inner corners. Raises ValueError."""
    try:
        c, r = (int(v) for v in str(text).lower().split('x'))
    except ValueError:
        raise ValueError('board size must look like "8x6" (inner corners), got %r' % (text,))
    if c < 2 or r < 2:
        raise ValueError('board size needs at least 2x2 inner corners, got %r' % (text,))
    return c, r


@dataclass
class StereoCalibrationResult:
    """Calibration outcome. ``left``/``right``: dicts K (3x3), D, R (3x3), P (3x4) [px] and
    ``std`` (standard deviations of fx, fy, cx, cy [px], k1, k2, p1, p2, k3);
    ``R``, ``T``: right camera pose w.r.t. the left (p_right = R p_left + T, T in m);
    ``holdout``: :func:`saras_calibration.accuracy.cross_validate` (``baseline_std``, ``T_std`` in m)."""
    left: dict
    right: dict
    R: np.ndarray
    T: np.ndarray
    size: tuple
    n_views: int
    reprojection_rms_px: tuple
    epipolar_rms_px: float
    stereo_rms_px: float
    holdout: dict
    corner_method: str
    left_yaml: str = field(repr=False)
    right_yaml: str = field(repr=False)

    @property
    def baseline_m(self):
        return float(np.linalg.norm(self.T))


class StereoSampleCollector:
    """Accumulates stereo image pairs showing a checkerboard, then calibrates.

    :param board: (cols, rows) inner corners; :param square: square side [m].
    :param left_name, right_name: ``camera_name`` written to the YAML files.
    :param corner_method: one of :data:`saras_calibration.corners.METHODS`.
    :param min_motion: a view is kept if its corners moved by more than this fraction of the
        image diagonal from every kept view (:func:`saras_calibration.views.is_new_view`).
    """

    def __init__(self, board, square, left_name='endoscope_left', right_name='endoscope_right',
                 max_views=60, corner_method='scaled_subpix', min_motion=0.015):
        if square <= 0 or not np.isfinite(square):
            raise ValueError('square size must be > 0 m, got %r' % (square,))
        if corner_method not in available_methods():
            raise ValueError('corner method %r unavailable here (one of %s)'
                             % (corner_method, ', '.join(available_methods())))
        cols, rows = board
        self.board = (int(cols), int(rows))
        self.square = float(square)
        self.info = ChessboardInfo('chessboard', cols, rows, float(square))
        self.cal = StereoCalibrator([self.info], pattern=Patterns.Chessboard)
        self.left_name, self.right_name = left_name, right_name
        self.max_views, self.corner_method, self.min_motion = int(max_views), corner_method, float(min_motion)
        self.size = None
        self.rejected = 0
        self.params, self.left, self.right = [], [], []

    @property
    def n_views(self):
        return len(self.left)

    @property
    def good_enough(self):
        """True when the views reach camera_calibration's coverage targets (all "green")."""
        return self.n_views > 0 and all(p[3] >= 1.0 for p in self.progress())

    def progress(self):
        """Coverage: list of (name, min, max, progress in [0, 1]) as camera_calibration's."""
        return [(n, lo, hi, p) for n, (lo, hi, p) in views.coverage(self.params).items()] if self.params else []

    def problems(self):
        """What the kept views lack (empty list when their coverage is sufficient)."""
        return views.coverage_problems(self.params)

    def _gray(self, img):
        if img is None or img.ndim not in (2, 3) or img.size == 0:
            return None
        return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img

    def add(self, left, right):
        """Offer a pair of grey (or BGR) images. Returns True if it was kept as a new view."""
        left, right = self._gray(left), self._gray(right)
        if left is None or right is None:
            self.rejected += 1
            return False
        size = (left.shape[1], left.shape[0])
        if (right.shape[1], right.shape[0]) != size or (self.size is not None and size != self.size):
            self.rejected += 1
            return False
        lc = detect_corners(left, self.board, self.corner_method)
        if lc is None or not views.is_new_view(lc, self.left, size, self.min_motion):
            return False
        params = self.cal.get_parameters(lc, None, self.info, size)
        slot = self._slot(params)
        if slot is None:
            return False
        rc = detect_corners(right, self.board, self.corner_method)
        if rc is None:
            return False
        self.size = size
        if slot == self.n_views:
            self.params.append(params)
            self.left.append(lc)
            self.right.append(rc)
        else:
            self.params[slot], self.left[slot], self.right[slot] = params, lc, rc
        return True

    def _slot(self, params):
        """Index the new view goes to: appended below ``max_views``; when full, it replaces the
        kept view closest to another one if that widens the coverage; None: dropped."""
        if self.n_views < self.max_views:
            return self.n_views
        p = np.asarray(self.params)
        d = np.abs(p[:, None, :] - p[None, :, :]).sum(axis=2)
        np.fill_diagonal(d, np.inf)
        worst = int(np.argmin(d.min(axis=1)))
        trial = list(self.params)
        trial[worst] = params

        def score(ps):
            return sum(v[2] for v in views.coverage(ps).values())
        return worst if score(trial) > score(self.params) + 1e-9 else None

    def check(self, min_views=DEFAULT_MIN_VIEWS):
        """Raise :class:`StereoCalibrationError` saying what is missing, if anything."""
        missing = []
        if self.n_views < min_views:
            missing.append('only %d stereo views with the board whole in both images (need %d)'
                           % (self.n_views, min_views))
        if self.n_views:
            missing += self.problems()
        if missing:
            raise StereoCalibrationError('; '.join(missing))

    def calibrate(self, min_views=DEFAULT_MIN_VIEWS, folds=13):
        """Calibrate (see :meth:`check`); ``folds``: hold-out groups (0: no hold-out)."""
        self.check(min_views)
        obj = accuracy.object_points(self.board, self.square)
        sol = accuracy.solve_stereo(obj, self.left, self.right, self.size)
        holdout = accuracy.cross_validate(obj, self.left, self.right, self.size, folds) if folds else {}
        c = self.cal
        c.size = c.l.size = c.r.size = self.size
        for mono, K, D in ((c.l, sol.Kl, sol.Dl), (c.r, sol.Kr, sol.Dr)):
            mono.intrinsics, mono.distortion = K.copy(), D.reshape(-1, 1).copy()
            mono.R, mono.P = np.eye(3), np.zeros((3, 4))
            mono.set_alpha(0.0)   # as MonoCalibrator.cal_fromcorners: P and the undistortion maps
        c.R, c.T = sol.R.copy(), sol.T.reshape(3, 1).copy()
        c.set_alpha(0.0)
        c.calibrated = True

        def cam(m, std):
            return {'K': m.intrinsics.copy(), 'D': np.ravel(m.distortion).copy(), 'R': m.R.copy(),
                    'P': m.P.copy(), 'std': std}

        return StereoCalibrationResult(
            left=cam(c.l, sol.std[0]), right=cam(c.r, sol.std[1]), R=sol.R.copy(), T=sol.T.copy(),
            size=tuple(self.size), n_views=self.n_views, reprojection_rms_px=sol.rms,
            epipolar_rms_px=accuracy.epipolar_rms(sol, self.left, self.right, self.size),
            stereo_rms_px=sol.stereo_rms, holdout=holdout, corner_method=self.corner_method,
            left_yaml=c.lryaml(self.left_name, c.l.distortion, c.l.intrinsics, c.l.R, c.l.P, self.size,
                               c.l.camera_model),
            right_yaml=c.lryaml(self.right_name, c.r.distortion, c.r.intrinsics, c.r.R, c.r.P, self.size,
                                c.r.camera_model))


def calibrate_stereo(left_images, right_images, board, square, min_views=DEFAULT_MIN_VIEWS, folds=13, **kwargs):
    """One-shot calibration from two lists of images (pairs with the board in both are used)."""
    if len(left_images) != len(right_images):
        raise StereoCalibrationError('%d left images but %d right images' % (len(left_images), len(right_images)))
    col = StereoSampleCollector(board, square, **kwargs)
    for l, r in zip(left_images, right_images):
        col.add(l, r)
    return col.calibrate(min_views=min_views, folds=folds)
