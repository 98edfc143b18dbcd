"""Rigid-transform helpers shared by the calibration core.

Conventions: 4x4 homogeneous numpy arrays ``T_a_b`` map points expressed in frame ``b`` into
frame ``a`` (``p_a = T_a_b @ p_b``). Translations are in metres, angles in radians unless a
name ends in ``_deg``. Quaternions are ``[x, y, z, w]`` (ROS order). ``rpy`` is the ROS/URDF
fixed-axis convention: roll about x, then pitch about y, then yaw about z
(``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``).
"""
import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    'NonRigidTransformError', 'validate_transform', 'validate_transforms', 'make_transform',
    'inverse', 'rotation_angle', 'rotation_angle_deg', 'transform_from_rpy', 'rpy_from_transform',
    'transform_from_quaternion', 'quaternion_from_transform', 'exp_se3_small', 'average_rotation',
    'transform_points',
]

#: Default tolerance on ``|R^T R - I|`` and ``|det R - 1|`` when validating a transform.
RIGID_TOLERANCE = 1e-5


class NonRigidTransformError(ValueError):
    """A matrix that should be a rigid transform (rotation + translation) is not one."""


def validate_transform(T, name='transform', tol=RIGID_TOLERANCE):
    """Return ``T`` as a float 4x4 array after checking it is a finite rigid transform.

    :param T: array-like 4x4 homogeneous matrix.
    :param name: name used in the error message (e.g. ``"ee_poses[3]"``).
    :param tol: tolerance on orthonormality, determinant and the last row.
    :raises NonRigidTransformError: wrong shape, NaN/inf, non-orthonormal or reflecting
        rotation, or last row different from ``[0, 0, 0, 1]``.
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
        raise NonRigidTransformError(
            '%s is not rigid: rotation determinant is %.6f (reflection or scale)' % (name, det))
    if np.max(np.abs(T[3] - np.array([0.0, 0.0, 0.0, 1.0]))) > tol:
        raise NonRigidTransformError('%s has last row %s, expected [0, 0, 0, 1]' % (name, T[3]))
    return T


def validate_transforms(Ts, name):
    """Validate a sequence of 4x4 transforms; returns an (N, 4, 4) array."""
    if Ts is None:
        raise ValueError('%s is None' % name)
    try:
        Ts = list(Ts)
    except TypeError:
        raise ValueError('%s must be a list of 4x4 transforms' % name)
    return np.array([validate_transform(T, '%s[%d]' % (name, i)) for i, T in enumerate(Ts)]).reshape(-1, 4, 4)


def make_transform(R=None, t=None):
    """Build a 4x4 transform from a 3x3 rotation and a translation [m]."""
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if t is not None:
        T[:3, 3] = np.ravel(t)
    return T


def inverse(T):
    """Inverse of a rigid transform (no general matrix inversion)."""
    Ti = np.eye(4)
    Ti[:3, :3] = T[:3, :3].T
    Ti[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return Ti


def rotation_angle(R):
    """Angle [rad] of rotation matrix ``R`` (robust near 0 and pi)."""
    return float(np.linalg.norm(Rotation.from_matrix(R).as_rotvec()))


def rotation_angle_deg(R):
    """Angle [deg] of rotation matrix ``R``."""
    return float(np.degrees(rotation_angle(R)))


def transform_from_rpy(xyz, rpy):
    """4x4 transform from a translation [m] and fixed-axis roll, pitch, yaw [rad]."""
    return make_transform(Rotation.from_euler('xyz', rpy).as_matrix(), xyz)


def rpy_from_transform(T):
    """(xyz [m], rpy [rad]) of a 4x4 transform, ROS fixed-axis convention."""
    return T[:3, 3].copy(), Rotation.from_matrix(T[:3, :3]).as_euler('xyz')


def transform_from_quaternion(xyz, quat_xyzw):
    """4x4 transform from translation [m] and quaternion ``[x, y, z, w]`` (normalised here)."""
    q = np.asarray(quat_xyzw, dtype=float)
    n = np.linalg.norm(q)
    if not np.isfinite(n) or n < 1e-9:
        raise NonRigidTransformError('quaternion %s has zero or invalid norm' % (q,))
    return make_transform(Rotation.from_quat(q / n).as_matrix(), xyz)


def quaternion_from_transform(T):
    """Quaternion ``[x, y, z, w]`` (w >= 0) of the rotation of ``T``."""
    q = Rotation.from_matrix(T[:3, :3]).as_quat()
    return q if q[3] >= 0 else -q


def exp_se3_small(rotvec, t):
    """Transform with rotation ``exp(rotvec)`` [rad] and translation ``t`` [m]."""
    return make_transform(Rotation.from_rotvec(rotvec).as_matrix(), t)


def average_rotation(Rs, weights=None):
    """Chordal L2 mean of rotation matrices (projection of the weighted sum onto SO(3))."""
    Rs = np.asarray(Rs, dtype=float)
    w = np.ones(len(Rs)) if weights is None else np.asarray(weights, dtype=float)
    M = np.einsum('i,ijk->jk', w, Rs)
    U, _, Vt = np.linalg.svd(M)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


def transform_points(T, points):
    """Apply a 4x4 transform to an (N, 3) array of points."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    return points @ T[:3, :3].T + T[:3, 3]
