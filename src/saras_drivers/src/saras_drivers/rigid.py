"""Small rigid-body helpers shared by the main-surgeon simulators (no ROS imports).

Conventions: homogeneous transforms are 4x4 numpy arrays ``T_a_b`` mapping coordinates in
frame ``b`` to frame ``a`` (``p_a = T_a_b @ p_b``); quaternions are ``(x, y, z, w)`` as in
geometry_msgs; lengths in metres, angles in radians.
"""
import math

import numpy as np


def rot_x(a):
    """Rotation matrix about x by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a):
    """Rotation matrix about y by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a):
    """Rotation matrix about z by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_to_matrix(roll, pitch, yaw):
    """Fixed-axis roll (x), then pitch (y), then yaw (z): ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def make_transform(R=None, t=None):
    """4x4 homogeneous transform from a 3x3 rotation and a translation [m]."""
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if t is not None:
        T[:3, 3] = t
    return T


def invert(T):
    """Inverse of a rigid 4x4 transform."""
    Ti = np.eye(4)
    Ti[:3, :3] = T[:3, :3].T
    Ti[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return Ti


def quaternion_from_matrix(R):
    """Unit quaternion ``(x, y, z, w)`` (w >= 0) of a 3x3 rotation matrix."""
    R = np.asarray(R, dtype=float)[:3, :3]
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0.0:
        s = math.sqrt(tr + 1.0) * 2.0
        w, x, y, z = 0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2]) * 2.0
        w, x, y, z = (R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s
    elif R[1, 1] > R[2, 2]:
        s = math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2]) * 2.0
        w, x, y, z = (R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s
    else:
        s = math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1]) * 2.0
        w, x, y, z = (R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s
    q = np.array([x, y, z, w])
    q /= np.linalg.norm(q)
    return q if q[3] >= 0.0 else -q


def matrix_from_quaternion(q):
    """3x3 rotation matrix of a quaternion ``(x, y, z, w)`` (normalised here)."""
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def transform_from_pose(xyz, quat):
    """4x4 transform from a translation [m] and a quaternion ``(x, y, z, w)``."""
    return make_transform(matrix_from_quaternion(quat), xyz)


def load_frames_file(path):
    """Read a world_frames YAML (saras_bringup format) into ``{child: (parent, T_parent_child)}``.

    Raises ``ValueError`` naming the offending entry on malformed content.
    """
    import yaml
    with open(path) as f:
        data = yaml.safe_load(f) or {}
    out = {}
    for i, e in enumerate(data.get('frames', [])):
        try:
            xyz = [float(v) for v in e['xyz']]
            rpy = [float(v) for v in e['rpy']]
            if len(xyz) != 3 or len(rpy) != 3 or not all(map(math.isfinite, xyz + rpy)):
                raise ValueError('xyz/rpy must be 3 finite numbers')
            out[str(e['child'])] = (str(e['parent']), make_transform(rpy_to_matrix(*rpy), xyz))
        except (KeyError, TypeError, ValueError) as ex:
            raise ValueError('%s: frames[%d] invalid: %s' % (path, i, ex))
    return out
