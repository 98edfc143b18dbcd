"""Which checkerboard views to keep, and whether a set of views is good enough (ROS-free).

A view is described by ``camera_calibration``'s four numbers (``Calibrator.get_parameters``):
X and Y (board centre across the usable image, 0..1), Size (sqrt of the board's image area
fraction) and Skew (tilt of the board, 0 = fronto-parallel).

Keeping: a view is new unless its corners are within ``min_motion`` (fraction of the image
diagonal, RMS over the corners) of a view already kept. A still board in a video stream gives
many copies of one view, which this rule drops; a board moved or turned by a few percent of the
image is kept (every one of the 13 pairs of OpenCV's stereo set: their closest two differ by
16.7 px, 2.1 % of the diagonal). camera_calibration's rule (the four numbers at an L1 distance
> 0.2) keeps only 8 of the 13.

Good enough to calibrate: at least ``min_views`` views and a coverage floor per number, as a
fraction of camera_calibration's "green" targets (X and Y span 0.7, Size up to 0.4, Skew up
to 0.5): :data:`MIN_PROGRESS`. Below it, :func:`coverage_problems` says what is missing.
"""
import numpy as np

__all__ = ['TARGET_RANGE', 'MIN_PROGRESS', 'is_new_view', 'coverage', 'coverage_problems']

#: camera_calibration's ``param_ranges``: the spread of X, Y, Size, Skew it asks for.
TARGET_RANGE = {'X': 0.7, 'Y': 0.7, 'Size': 0.4, 'Skew': 0.5}
#: Least fraction of :data:`TARGET_RANGE` a set must cover (OpenCV's stereo set: X 0.77,
#: Y 0.51, Size 1.0, Skew 1.0 on the left camera).
MIN_PROGRESS = {'X': 0.3, 'Y': 0.3, 'Size': 0.5, 'Skew': 0.3}
_NAMES = ('X', 'Y', 'Size', 'Skew')
_ADVICE = {
    'X': 'horizontal coverage: show the board near the left and the right image edges',
    'Y': 'vertical coverage: show the board near the top and the bottom image edges',
    'Size': 'scale: bring the board closer so that it fills a larger part of the image',
    'Skew': 'tilt: tilt the board by 30-45 deg about its horizontal and its vertical axis',
}


def is_new_view(corners, kept, image_size, min_motion=0.015):
    """True if ``corners`` differ from every array in ``kept`` by more than ``min_motion`` times
    the image diagonal (RMS corner displacement)."""
    c = np.asarray(corners, np.float64).reshape(-1, 2)
    limit = min_motion * float(np.hypot(*image_size))
    for k in kept:
        k = np.asarray(k, np.float64).reshape(-1, 2)
        if k.shape == c.shape and np.sqrt(np.mean(np.sum((k - c) ** 2, axis=1))) <= limit:
            return False
    return True


def coverage(params):
    """``{name: (low, high, progress)}`` over view parameters ``[X, Y, Size, Skew]`` (as
    camera_calibration: Size and Skew count from 0, only large boards and strong tilts help)."""
    if len(params) == 0:
        return {n: (0.0, 0.0, 0.0) for n in _NAMES}
    p = np.asarray(params, np.float64).reshape(-1, 4)
    lo, hi = p.min(axis=0), p.max(axis=0)
    lo[2:] = 0.0
    return {n: (float(lo[i]), float(hi[i]), float(min(1.0, (hi[i] - lo[i]) / TARGET_RANGE[n])))
            for i, n in enumerate(_NAMES)}


def coverage_problems(params, min_progress=None):
    """List of human-readable reasons (empty when the views cover enough)."""
    floor = dict(MIN_PROGRESS, **(min_progress or {}))
    problems = []
    for name, (lo, hi, prog) in coverage(params).items():
        if prog < floor[name]:
            span = 'spans %.2f-%.2f' % (lo, hi) if name in ('X', 'Y') else 'reaches %.2f' % hi
            problems.append('%s (%s %s, %.0f %% of the target %.2f; at least %.0f %% needed)'
                            % (_ADVICE[name], name, span, 100 * prog, TARGET_RANGE[name], 100 * floor[name]))
    return problems
