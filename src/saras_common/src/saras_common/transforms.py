"""Rigid transforms of the SARAS platform: the one implementation (numpy; ROS messages optional).

Conventions:

* ``T_a_b`` is a 4x4 homogeneous numpy array mapping points of frame ``b`` into frame ``a``
  (``p_a = T_a_b @ p_b``); rotations alone are 3x3.
* Lengths in metres, angles in radians unless a name ends in ``_deg``.
* Quaternions are in ROS order ``(x, y, z, w)``; the ones returned here have ``w >= 0``.
* ``rpy`` is the URDF / tf fixed-axis convention: roll about x, then pitch about y, then yaw
  about z, i.e. ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.

The functions at the end convert to and from ``geometry_msgs`` (Pose, Transform,
TransformStamped). They import ``geometry_msgs`` only when they construct a message, so the rest of
the module works without ROS.
"""
import math

import numpy as np

__all__ = [
    'RIGID_TOLERANCE', 'NonRigidTransformError',
    'make_transform', 'translation', 'rot_x', 'rot_y', 'rot_z', 'axis_angle', 'transform_from_rotvec',
    'rpy_to_matrix', 'matrix_to_rpy', 'transform_from_rpy', 'rpy_from_transform',
    'quaternion_to_matrix', 'quaternion_from_matrix', 'transform_from_quaternion', 'quaternion_from_transform',
    'inverse', 'transform_points', 'rotation_angle', 'rotation_angle_deg', 'average_rotation', 'wrap_angle',
    'validate_transform', 'validate_transforms',
    'pose_to_matrix', 'transform_msg_to_matrix', 'set_pose_msg', 'set_transform_msg', 'matrix_to_pose',
    'matrix_to_transform_msg', 'transform_stamped',
]

#: Default tolerance on ``|R^T R - I|``, ``|det R - 1|`` and the last row in :func:`validate_transform`.
RIGID_TOLERANCE = 1e-5


class NonRigidTransformError(ValueError):
    """A matrix that should be a rigid transform (rotation + translation) is not one."""


# --- construction -------------------------------------------------------------------------------

def make_transform(R=None, t=None):
    """4x4 transform from a 3x3 rotation (default identity) and a translation [m] (default 0)."""
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if t is not None:
        T[:3, 3] = np.ravel(t)
    return T


def translation(x=0.0, y=0.0, z=0.0):
    """4x4 pure translation [m]."""
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def rot_x(angle):
    """4x4 rotation about x by ``angle`` [rad]."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0, 0.0], [0.0, c, -s, 0.0], [0.0, s, c, 0.0], [0.0, 0.0, 0.0, 1.0]])


def rot_y(angle):
    """4x4 rotation about y by ``angle`` [rad]."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s, 0.0], [0.0, 1.0, 0.0, 0.0], [-s, 0.0, c, 0.0], [0.0, 0.0, 0.0, 1.0]])


def rot_z(angle):
    """4x4 rotation about z by ``angle`` [rad]."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def _skew(k):
    return np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])


def axis_angle(axis, angle):
    """4x4 rotation of ``angle`` [rad] about the 3-vector ``axis`` (normalised here; Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    n = np.linalg.norm(k)
    if not n > 0.0:
        raise ValueError('rotation axis %s has zero length' % (k,))
    kx = _skew(k / n)
    T = np.eye(4)
    T[:3, :3] = np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)
    return T


def transform_from_rotvec(rotvec, t=None):
    """4x4 transform with rotation ``exp(rotvec)`` (axis * angle [rad]) and translation ``t`` [m]."""
    w = np.asarray(rotvec, dtype=float)
    angle = float(np.linalg.norm(w))
    if angle < 1e-12:
        return make_transform(np.eye(3) + _skew(w), t)
    T = axis_angle(w, angle)
    if t is not None:
        T[:3, 3] = np.ravel(t)
    return T


# --- Euler angles and quaternions ----------------------------------------------------------------

def rpy_to_matrix(rpy):
    """3x3 rotation of fixed-axis ``(roll, pitch, yaw)`` [rad] (URDF ``rpy``)."""
    roll, pitch, yaw = rpy
    return (rot_z(yaw) @ rot_y(pitch) @ rot_x(roll))[:3, :3]


def matrix_to_rpy(R):
    """``(roll, pitch, yaw)`` [rad] of a 3x3 (or 4x4) rotation, pitch in [-pi/2, pi/2]; at gimbal
    lock the roll is 0 and the rotation about z goes into yaw."""
    R = np.asarray(R, dtype=float)
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) < 1e-12:
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def transform_from_rpy(xyz, rpy):
    """4x4 transform from a translation [m] and fixed-axis ``rpy`` [rad]."""
    return make_transform(rpy_to_matrix(rpy), xyz)


def rpy_from_transform(T):
    """``(xyz [m], rpy [rad])`` of a 4x4 transform, as numpy arrays."""
    return np.array(T[:3, 3], dtype=float), np.array(matrix_to_rpy(T))


def quaternion_to_matrix(q):
    """3x3 rotation of a quaternion ``(x, y, z, w)`` (normalised here).

    :raises ValueError: zero, NaN or infinite quaternion.
    """
    q = np.asarray(q, dtype=float)
    n = np.linalg.norm(q)
    if not (np.isfinite(n) and n > 1e-12):
        raise ValueError('quaternion %s has zero or invalid norm' % (q,))
    x, y, z, w = q / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def quaternion_from_matrix(R):
    """Unit quaternion ``(x, y, z, w)`` with ``w >= 0`` of a 3x3 (or 4x4) rotation (Shepperd)."""
    r = np.asarray(R, dtype=float)[:3, :3]
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = np.array([(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s])
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = np.array([0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s])
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = np.array([(r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s])
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = np.array([(r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s])
    q /= np.linalg.norm(q)
    return q if q[3] >= 0.0 else -q


def transform_from_quaternion(xyz, q):
    """4x4 transform from a translation [m] and a quaternion ``(x, y, z, w)`` (normalised here)."""
    return make_transform(quaternion_to_matrix(q), xyz)


def quaternion_from_transform(T):
    """Quaternion ``(x, y, z, w)``, ``w >= 0``, of the rotation of a 4x4 transform."""
    return quaternion_from_matrix(T)


# --- operations ------------------------------------------------------------------------------------

def inverse(T):
    """Inverse of a rigid 4x4 transform (transpose of the rotation, no general inversion)."""
    Ti = np.eye(4)
    Ti[:3, :3] = T[:3, :3].T
    Ti[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return Ti


def transform_points(T, points):
    """``T`` applied to an (N, 3) array of points [m]; returns (N, 3)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    return points @ T[:3, :3].T + T[:3, 3]


def rotation_angle(R):
    """Angle [rad] in [0, pi] of a 3x3 (or 4x4) rotation; accurate near 0 and near pi."""
    r = np.asarray(R, dtype=float)[:3, :3]
    s = 0.5 * np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    c = 0.5 * (np.trace(r) - 1.0)
    return float(math.atan2(s, c))


def rotation_angle_deg(R):
    """Angle [deg] of a rotation."""
    return math.degrees(rotation_angle(R))


def average_rotation(Rs, weights=None):
    """Chordal L2 mean of 3x3 rotations (the weighted sum projected onto SO(3))."""
    Rs = np.asarray(Rs, dtype=float)
    w = np.ones(len(Rs)) if weights is None else np.asarray(weights, dtype=float)
    U, _, Vt = np.linalg.svd(np.einsum('i,ijk->jk', w, Rs))
    return U @ np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))]) @ Vt


def wrap_angle(angle):
    """``angle`` [rad] wrapped into (-pi, pi]."""
    a = math.fmod(angle + math.pi, 2.0 * math.pi)
    if a <= 0.0:
        a += 2.0 * math.pi
    return a - math.pi


# --- validation ------------------------------------------------------------------------------------

def validate_transform(T, name='transform', tol=RIGID_TOLERANCE):
    """``T`` as a float 4x4 array after checking that it is a finite rigid transform.

    :param name: what the error message calls it (e.g. ``"ee_poses[3]"``).
    :raises NonRigidTransformError: wrong shape, NaN/inf, non-orthonormal or reflecting rotation,
        or a last row other than ``[0, 0, 0, 1]`` (each beyond ``tol``).
    """
    try:
        T = np.asarray(T, dtype=float)
    except (TypeError, ValueError) as exc:
        raise NonRigidTransformError('%s is not a numeric 4x4 matrix (%s)' % (name, exc))
    if T.shape != (4, 4):
        raise NonRigidTransformError('%s must be 4x4, got shape %s' % (name, T.shape))
    if not np.all(np.isfinite(T)):
        raise NonRigidTransformError('%s contains NaN or inf' % name)
    R = T[:3, :3]
    ortho = np.max(np.abs(R.T @ R - np.eye(3)))
    if ortho > tol:
        raise NonRigidTransformError(
            '%s is not rigid: rotation block is not orthonormal (max |R^T R - I| = %.3g)' % (name, ortho))
    det = np.linalg.det(R)
    if abs(det - 1.0) > tol:
        raise NonRigidTransformError('%s is not rigid: rotation determinant is %.6f (reflection or scale)'
                                     % (name, det))
    if np.max(np.abs(T[3] - np.array([0.0, 0.0, 0.0, 1.0]))) > tol:
        raise NonRigidTransformError('%s has last row %s, expected [0, 0, 0, 1]' % (name, T[3]))
    return T


def validate_transforms(Ts, name):
    """:func:`validate_transform` over a sequence; returns an (N, 4, 4) array."""
    if Ts is None:
        raise ValueError('%s is None' % name)
    try:
        Ts = list(Ts)
    except TypeError:
        raise ValueError('%s must be a list of 4x4 transforms' % name)
    return np.array([validate_transform(T, '%s[%d]' % (name, i)) for i, T in enumerate(Ts)]).reshape(-1, 4, 4)


# --- geometry_msgs ---------------------------------------------------------------------------------

def _xyzq_to_matrix(xyz, q, norm_tolerance, what):
    v = np.array(list(xyz) + list(q), dtype=float)
    if not np.all(np.isfinite(v)):
        raise ValueError('%s contains NaN or inf' % what)
    n = np.linalg.norm(v[3:])
    if norm_tolerance is not None and abs(n - 1.0) > norm_tolerance:
        raise ValueError('%s quaternion norm %.4f is not 1' % (what, n))
    return transform_from_quaternion(v[:3], v[3:])


def pose_to_matrix(pose, norm_tolerance=0.01):
    """geometry_msgs/Pose -> 4x4.

    :param norm_tolerance: largest accepted ``| |q| - 1 |`` (None: any non-zero quaternion).
    :raises ValueError: NaN/inf, or a quaternion norm outside the tolerance.
    """
    p, q = pose.position, pose.orientation
    return _xyzq_to_matrix((p.x, p.y, p.z), (q.x, q.y, q.z, q.w), norm_tolerance, 'pose')


def transform_msg_to_matrix(transform, norm_tolerance=0.01):
    """geometry_msgs/Transform -> 4x4 (same checks as :func:`pose_to_matrix`)."""
    t, q = transform.translation, transform.rotation
    return _xyzq_to_matrix((t.x, t.y, t.z), (q.x, q.y, q.z, q.w), norm_tolerance, 'transform')


def set_pose_msg(pose, xyz, q):
    """Write position ``xyz`` [m] and orientation ``q`` (x, y, z, w) into a geometry_msgs/Pose in
    place (no allocation); returns ``pose``."""
    p, o = pose.position, pose.orientation
    p.x, p.y, p.z = float(xyz[0]), float(xyz[1]), float(xyz[2])
    o.x, o.y, o.z, o.w = float(q[0]), float(q[1]), float(q[2]), float(q[3])
    return pose


def set_transform_msg(transform, xyz, q):
    """Write translation ``xyz`` [m] and rotation ``q`` (x, y, z, w) into a
    geometry_msgs/Transform in place (no allocation); returns ``transform``."""
    t, r = transform.translation, transform.rotation
    t.x, t.y, t.z = float(xyz[0]), float(xyz[1]), float(xyz[2])
    r.x, r.y, r.z, r.w = float(q[0]), float(q[1]), float(q[2]), float(q[3])
    return transform


def matrix_to_pose(T):
    """4x4 -> new geometry_msgs/Pose."""
    from geometry_msgs.msg import Pose
    return set_pose_msg(Pose(), T[:3, 3], quaternion_from_matrix(T))


def matrix_to_transform_msg(T):
    """4x4 -> new geometry_msgs/Transform."""
    from geometry_msgs.msg import Transform
    return set_transform_msg(Transform(), T[:3, 3], quaternion_from_matrix(T))


def transform_stamped(parent, child, T=None, stamp=None, xyz=None, q=None):
    """New geometry_msgs/TransformStamped ``parent -> child`` from a 4x4 ``T`` or from ``xyz`` [m]
    and ``q`` (x, y, z, w); ``stamp`` a rospy.Time (default: zero time)."""
    from geometry_msgs.msg import TransformStamped
    msg = TransformStamped()
    msg.header.frame_id, msg.child_frame_id = parent, child
    if stamp is not None:
        msg.header.stamp = stamp
    if T is not None:
        xyz, q = T[:3, 3], quaternion_from_matrix(T)
    set_transform_msg(msg.transform, xyz, q)
    return msg
