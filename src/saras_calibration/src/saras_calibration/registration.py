"""Base-frame registration: three-point frames and least-squares rigid registration.

* :func:`frame_from_three_points`: the classic three-point tool/fixture calibration
  (origin, a point on +x, a point in the xy half-plane with y > 0).
* :func:`register_points`: least-squares rigid transform (Kabsch / Umeyama without scale)
  between N >= 3 corresponding points, e.g. pattern dots touched by a robot tool tip.

Points are in metres; returned transforms are 4x4 numpy arrays.
"""
import numpy as np

from saras_common.transforms import make_transform

__all__ = ['RegistrationError', 'frame_from_three_points', 'register_points']

#: Minimum spread [m] of touched points perpendicular to their best-fit line (below: collinear).
MIN_SPREAD_M = 1e-3


class RegistrationError(ValueError):
    """Bad input to a registration (fewer than 3 points, collinear points, NaN, ...)."""


def _points(p, name, n=None):
    try:
        a = np.asarray(p, dtype=float)
    except (TypeError, ValueError):
        raise RegistrationError('%s must be numeric 3-D points' % name)
    if a.ndim == 1:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] != 3:
        raise RegistrationError('%s must be an (N, 3) array of points, got shape %s' % (name, a.shape))
    if not np.all(np.isfinite(a)):
        raise RegistrationError('%s contains NaN or inf' % name)
    return a


def frame_from_three_points(p_origin, p_x, p_plane, min_distance=MIN_SPREAD_M):
    """Frame defined by three touched points.

    The origin is ``p_origin``; x points from ``p_origin`` to ``p_x``; z is normal to the plane
    of the three points, oriented so that ``p_plane`` has a positive y coordinate.

    :param p_origin, p_x, p_plane: 3-D points [m] in the robot base frame.
    :param min_distance: minimum distance [m] between points and of ``p_plane`` from the x axis.
    :returns: 4x4 ``T_base_frame``.
    :raises RegistrationError: NaN input, coincident or collinear points.
    """
    o = _points(p_origin, 'p_origin')[0]
    px = _points(p_x, 'p_x')[0]
    pp = _points(p_plane, 'p_plane')[0]
    x = px - o
    if np.linalg.norm(x) < min_distance:
        raise RegistrationError('p_x is %.3g m from p_origin (< %.3g m): points coincide'
                                % (np.linalg.norm(x), min_distance))
    x /= np.linalg.norm(x)
    v = pp - o
    y = v - (v @ x) * x
    if np.linalg.norm(y) < min_distance:
        raise RegistrationError('collinear points: p_plane is %.3g m from the x axis (< %.3g m)'
                                % (np.linalg.norm(y), min_distance))
    y /= np.linalg.norm(y)
    z = np.cross(x, y)
    return make_transform(np.column_stack([x, y, z]), o)


def register_points(points_in_robot, points_in_pattern, min_spread=MIN_SPREAD_M):
    """Least-squares rigid transform ``T_robot_pattern`` with ``p_robot ~= T @ p_pattern``.

    Kabsch/Umeyama (no scale) on N >= 3 non-collinear corresponding points.

    :param points_in_robot: (N, 3) points measured in the robot base frame [m].
    :param points_in_pattern: (N, 3) same points in the pattern frame [m].
    :param min_spread: minimum spread [m] of the pattern points off their best-fit line.
    :returns: (4x4 ``T_robot_pattern``, rms residual [m]).
    :raises RegistrationError: fewer than 3 points, mismatched counts, NaN, collinear points.
    """
    P = _points(points_in_pattern, 'points_in_pattern')
    Q = _points(points_in_robot, 'points_in_robot')
    if len(P) != len(Q):
        raise RegistrationError('mismatched point counts: %d in robot, %d in pattern' % (len(Q), len(P)))
    if len(P) < 3:
        raise RegistrationError('registration needs at least 3 points, got %d' % len(P))
    pc, qc = P.mean(axis=0), Q.mean(axis=0)
    P0, Q0 = P - pc, Q - qc
    for name, A in (('points_in_pattern', P0), ('points_in_robot', Q0)):
        sv = np.linalg.svd(A, compute_uv=False)
        spread = sv[1] / np.sqrt(len(A))
        if spread < min_spread:
            raise RegistrationError('collinear points in %s: spread off the best-fit line is %.3g m '
                                    '(< %.3g m); touch points around the circle' % (name, spread, min_spread))
    H = P0.T @ Q0
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    t = qc - R @ pc
    res = Q - (P @ R.T + t)
    return make_transform(R, t), float(np.sqrt(np.mean(np.sum(res ** 2, axis=1))))
