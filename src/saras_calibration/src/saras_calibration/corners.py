"""Checkerboard corner detection and sub-pixel refinement (ROS-free).

Every method returns the ``cols x rows`` inner corners as a float32 ``(N, 1, 2)`` array in
pixels, row by row, first corner above the last one (the order ``camera_calibration`` uses, so
the left and right views of a pair match), or ``None`` when the board is not found whole.

Methods (``bench/stereo_corners_bench.py`` compares them on OpenCV's real stereo set):

``scaled_subpix`` (default)
    ``cv2.findChessboardCorners`` then ``cv2.cornerSubPix`` with a half window of
    ``window_fraction`` (0.3) times the smallest distance between neighbouring corners of this
    view, clamped to ``window_clamp`` (2..11 px). The window then stays inside the squares that
    meet at the corner: a larger one reaches the board's outer edge (outer corners are pulled
    towards it) or the next corner.
``subpix11``
    OpenCV's calibration sample: ``cornerSubPix`` with a fixed 11x11 half window.
``sb``
    ``cv2.findChessboardCornersSB`` (sector based, ``CALIB_CB_ACCURACY``); finds fewer boards.
``camera_calibration``
    ROS ``camera_calibration``'s own detector (half window = half the corner spacing).
``mrgingham``
    mrgingham's ChESS corner features (``python3-mrgingham``) matched to the OpenCV grid
    (mrgingham itself only identifies square N x N boards).
"""
import cv2
import numpy as np

__all__ = ['METHODS', 'CornerError', 'detect_corners', 'refine_window', 'min_corner_spacing', 'available_methods']

METHODS = ('scaled_subpix', 'subpix11', 'sb', 'camera_calibration', 'mrgingham')
#: Corners closer than this to the image border [px] reject the view (camera_calibration's rule).
BORDER_PX = 8
_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
_FIND_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK


class CornerError(ValueError):
    """Unknown method or unusable input."""


def available_methods():
    """The methods usable here (``mrgingham`` needs python3-mrgingham)."""
    try:
        import mrgingham  # noqa: F401
        return METHODS
    except ImportError:
        return tuple(m for m in METHODS if m != 'mrgingham')


def min_corner_spacing(corners, board):
    """Smallest distance [px] between horizontally or vertically neighbouring corners."""
    cols, rows = board
    g = np.asarray(corners, np.float64).reshape(rows, cols, 2)
    dx = np.linalg.norm(np.diff(g, axis=1), axis=2)
    dy = np.linalg.norm(np.diff(g, axis=0), axis=2)
    return float(min(dx.min(), dy.min()))


def refine_window(corners, board, fraction=0.3, clamp=(2, 11)):
    """Half size [px] of the ``cornerSubPix`` window for this view (see module doc)."""
    return int(np.clip(round(fraction * min_corner_spacing(corners, board)), clamp[0], clamp[1]))


def _gray(image):
    if image is None or image.ndim not in (2, 3) or image.size == 0:
        raise CornerError('expected a grey or BGR image')
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image


def _orient(corners, board):
    """camera_calibration's order: rectangular boards top to bottom; square boards with the
    first corner at the top left."""
    cols, rows = board
    c = np.ascontiguousarray(corners, np.float32).reshape(-1, 1, 2)
    if cols != rows:
        return c[::-1].copy() if c[0, 0, 1] > c[-1, 0, 1] else c
    g = c.reshape(rows, cols, 2)
    for _ in range(4):
        d = g[-1, -1] - g[0, 0]
        if d[0] >= 0 and d[1] >= 0:
            break
        g = np.rot90(g)
    return np.ascontiguousarray(g).reshape(-1, 1, 2)


def _inside(corners, shape):
    h, w = shape[:2]
    c = corners.reshape(-1, 2)
    return bool(np.all((c[:, 0] > BORDER_PX) & (c[:, 0] < w - BORDER_PX) &
                       (c[:, 1] > BORDER_PX) & (c[:, 1] < h - BORDER_PX)))


def _find(gray, board):
    ok, c = cv2.findChessboardCorners(gray, tuple(board), flags=_FIND_FLAGS)
    return c if ok and _inside(c, gray.shape) else None


def _subpix(gray, corners, half):
    return cv2.cornerSubPix(gray, corners, (half, half), (-1, -1), _CRITERIA)


def _mrgingham(gray, board, coarse):
    import mrgingham
    feats = mrgingham.find_chessboard_corners(np.ascontiguousarray(gray))
    if feats is None or len(feats) < board[0] * board[1]:
        return None
    c = coarse.reshape(-1, 2)
    d = np.linalg.norm(feats[None, :, :] - c[:, None, :], axis=2)
    j = d.argmin(axis=1)
    if np.any(d[np.arange(len(c)), j] > 0.3 * min_corner_spacing(coarse, board)) or len(set(j)) != len(c):
        return None
    return feats[j].astype(np.float32).reshape(-1, 1, 2)


def detect_corners(image, board, method='scaled_subpix', window_fraction=0.3, window_clamp=(2, 11)):
    """Inner corners of a ``board = (cols, rows)`` checkerboard in ``image`` (see module doc)."""
    if method not in METHODS:
        raise CornerError('unknown corner method %r (one of %s)' % (method, ', '.join(METHODS)))
    gray = _gray(image)
    board = (int(board[0]), int(board[1]))
    if method == 'sb':
        flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
        ok, c = cv2.findChessboardCornersSB(gray, board, flags=flags)
        return _orient(c, board) if ok and _inside(c, gray.shape) else None
    if method == 'camera_calibration':
        from camera_calibration.calibrator import ChessboardInfo, _get_corners
        ok, c = _get_corners(gray, ChessboardInfo('chessboard', board[0], board[1], 1.0), True,
                             cv2.CALIB_CB_FAST_CHECK)
        return _orient(c, board) if ok else None
    c = _find(gray, board)
    if c is None:
        return None
    if method == 'subpix11':
        c = _subpix(gray, c, 11)
    elif method == 'mrgingham':
        c = _mrgingham(gray, board, c)
    else:
        c = _subpix(gray, c, refine_window(c, board, window_fraction, window_clamp))
    return None if c is None else _orient(c, board)
