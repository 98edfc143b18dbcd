"""Headless stereo calibration of the endoscope on top of ROS ``camera_calibration``.

The calibrator classes of ``camera_calibration`` (Zhang intrinsics with the plumb-bob model,
``cv2.stereoCalibrate`` with fixed intrinsics, ``cv2.stereoRectify``) do the numerics; this
module feeds them image pairs without a GUI, applies the same sample-diversity rule as the
interactive tool, and reports quality numbers the GUI does not keep:

* reprojection RMS [px] of every accepted view with the calibrated intrinsics (per camera),
* epipolar RMS [px]: vertical disparity of matching corners after rectification,
* baseline [m] and the camera_info YAML text of each camera (``camera_calibration_parsers``
  format, the one ``camera_info_manager`` and the endoscope driver load).
"""
from dataclasses import dataclass, field

import cv2
import numpy as np
from camera_calibration.calibrator import ChessboardInfo, Patterns, StereoCalibrator

__all__ = ['StereoCalibrationError', 'StereoSampleCollector', 'StereoCalibrationResult', 'calibrate_stereo',
           'parse_board_size']


class StereoCalibrationError(RuntimeError):
    """Calibration impossible (no board found, too few views, inconsistent images)."""


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
    """Calibration outcome. ``left``/``right``: dicts K (3x3), D, R (3x3), P (3x4) [px];
    ``R``, ``T``: right camera pose w.r.t. the left (OpenCV stereoCalibrate, T in m)."""
    left: dict
    right: dict
    R: np.ndarray
    T: np.ndarray
    size: tuple
    n_views: int
    reprojection_rms_px: tuple
    epipolar_rms_px: float
    left_yaml: str = field(repr=False)
    right_yaml: str = field(repr=False)

    @property
    def baseline_m(self):
        return float(np.linalg.norm(self.T))


class StereoSampleCollector:
    """Accumulates stereo image pairs showing a checkerboard, then calibrates.

    :param board: (cols, rows) inner corners; :param square: square side [m].
    :param left_name, right_name: ``camera_name`` written to the YAML files.
    """

    def __init__(self, board, square, left_name='endoscope_left', right_name='endoscope_right',
                 max_views=60):
        if square <= 0 or not np.isfinite(square):
            raise ValueError('square size must be > 0 m, got %r' % (square,))
        cols, rows = board
        self.board = ChessboardInfo('chessboard', cols, rows, float(square))
        self.cal = StereoCalibrator([self.board], pattern=Patterns.Chessboard,
                                    checkerboard_flags=cv2.CALIB_CB_FAST_CHECK)
        self.left_name, self.right_name = left_name, right_name
        self.max_views = int(max_views)
        self.size = None
        self.rejected = 0

    @property
    def n_views(self):
        return len(self.cal.good_corners)

    @property
    def good_enough(self):
        """True when the views cover enough position/size/skew (camera_calibration's rule)."""
        self.cal.compute_goodenough()
        return bool(self.cal.goodenough)

    def progress(self):
        """camera_calibration's coverage: list of (name, min, max, progress in [0, 1])."""
        return self.cal.compute_goodenough() or []

    def add(self, left, right):
        """Offer a pair of grey (or BGR) images. Returns True if it was kept as a new view."""
        for img in (left, right):
            if img is None or img.ndim not in (2, 3) or img.size == 0:
                self.rejected += 1
                return False
        left = cv2.cvtColor(left, cv2.COLOR_BGR2GRAY) if left.ndim == 3 else left
        right = cv2.cvtColor(right, cv2.COLOR_BGR2GRAY) if right.ndim == 3 else right
        size = (left.shape[1], left.shape[0])
        if (right.shape[1], right.shape[0]) != size or (self.size is not None and size != self.size):
            self.rejected += 1
            return False
        if self.n_views >= self.max_views:
            return False
        c = self.cal
        _, lcorners, _, lids, lboard, _ = c.downsample_and_detect(left)
        _, rcorners, _, rids, _, _ = c.downsample_and_detect(right)
        if lcorners is None or rcorners is None or len(lcorners) != len(rcorners):
            return False
        params = c.get_parameters(lcorners, lids, lboard, size)
        if not c.is_good_sample(params, lcorners, lids, c.last_frame_corners, c.last_frame_ids):
            return False
        self.size = size
        c.db.append((params, left, right))
        c.good_corners.append((lcorners, rcorners, lids, rids, lboard))
        return True

    def calibrate(self, min_views=8):
        """Run the calibration. Raises :class:`StereoCalibrationError` with fewer than ``min_views``."""
        if self.n_views < min_views:
            raise StereoCalibrationError('only %d stereo views with the board in both images (need %d)'
                                         % (self.n_views, min_views))
        c = self.cal
        c.size = self.size
        c.l.size = c.r.size = self.size
        c.cal_fromcorners(c.good_corners)
        c.calibrated = True
        return self._result()

    def _reprojection_rms(self, mono, corner_index):
        b = self.board
        obj = np.zeros((b.n_cols * b.n_rows, 3))
        obj[:, 0] = np.arange(b.n_cols * b.n_rows) // b.n_cols * b.dim
        obj[:, 1] = np.arange(b.n_cols * b.n_rows) % b.n_cols * b.dim
        sq, n = 0.0, 0
        for g in self.cal.good_corners:
            img = g[corner_index].reshape(-1, 2).astype(np.float64)
            ok, rv, tv = cv2.solvePnP(obj, img, mono.intrinsics, mono.distortion)
            proj, _ = cv2.projectPoints(obj, rv, tv, mono.intrinsics, mono.distortion)
            sq += float(np.sum((proj.reshape(-1, 2) - img) ** 2))
            n += len(img)
        return float(np.sqrt(sq / n))

    def _result(self):
        c = self.cal
        epi = []
        for (lco, rco, _, _, _) in c.good_corners:
            epi.append(c.epipolar_error(c.l.undistort_points(lco), c.r.undistort_points(rco)) ** 2)

        def cam(m):
            return {'K': m.intrinsics.copy(), 'D': np.ravel(m.distortion).copy(), 'R': m.R.copy(), 'P': m.P.copy()}

        return StereoCalibrationResult(
            left=cam(c.l), right=cam(c.r), R=c.R.copy(), T=np.ravel(c.T).copy(), size=tuple(self.size),
            n_views=self.n_views,
            reprojection_rms_px=(self._reprojection_rms(c.l, 0), self._reprojection_rms(c.r, 1)),
            epipolar_rms_px=float(np.sqrt(np.mean(epi))),
            left_yaml=c.lryaml(self.left_name, c.l.distortion, c.l.intrinsics, c.l.R, c.l.P, self.size, c.l.camera_model),
            right_yaml=c.lryaml(self.right_name, c.r.distortion, c.r.intrinsics, c.r.R, c.r.P, self.size, c.r.camera_model))


def calibrate_stereo(left_images, right_images, board, square, min_views=8, **kwargs):
    """One-shot calibration from two lists of images (pairs with the board in both are used)."""
    if len(left_images) != len(right_images):
        raise StereoCalibrationError('%d left images but %d right images' % (len(left_images), len(right_images)))
    col = StereoSampleCollector(board, square, **kwargs)
    for l, r in zip(left_images, right_images):
        col.add(l, r)
    return col.calibrate(min_views=min_views)
