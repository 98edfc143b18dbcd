"""Homogeneous-transform helpers (numpy, no ROS).

Conventions: 4x4 matrices ``T`` map points of the child frame into the parent frame
(``p_parent = T @ p_child``); lengths in metres, angles in radians; ``rpy`` is the URDF /
tf convention (fixed axes: roll about x, then pitch about y, then yaw about z, i.e.
``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``); quaternions are ROS-ordered ``(x, y, z, w)``.
"""
import math

import numpy as np


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


def trans(x=0.0, y=0.0, z=0.0):
    """4x4 pure translation [m]."""
    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t


def rpy_to_matrix(rpy):
    """3x3 rotation of fixed-axis roll, pitch, yaw [rad] (URDF ``rpy``)."""
    roll, pitch, yaw = rpy
    return (rot_z(yaw) @ rot_y(pitch) @ rot_x(roll))[:3, :3]


def matrix_to_rpy(rot):
    """Inverse of :func:`rpy_to_matrix`; pitch in [-pi/2, pi/2]."""
    rot = np.asarray(rot)
    pitch = math.atan2(-rot[2, 0], math.hypot(rot[0, 0], rot[1, 0]))
    if abs(math.cos(pitch)) < 1e-12:  # gimbal lock: put everything into yaw
        return 0.0, pitch, math.atan2(-rot[0, 1], rot[1, 1])
    return math.atan2(rot[2, 1], rot[2, 2]), pitch, math.atan2(rot[1, 0], rot[0, 0])


def xyz_rpy(xyz, rpy):
    """4x4 transform from a translation [m] and URDF ``rpy`` [rad]."""
    t = np.eye(4)
    t[:3, :3] = rpy_to_matrix(rpy)
    t[:3, 3] = xyz
    return t


def axis_angle(axis, angle):
    """4x4 rotation of ``angle`` [rad] about the unit 3-vector ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    t = np.eye(4)
    t[:3, :3] = np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)
    return t


def quat_to_matrix(quat):
    """3x3 rotation of a ROS quaternion ``(x, y, z, w)`` (normalised here)."""
    x, y, z, w = np.asarray(quat, dtype=float) / np.linalg.norm(quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def matrix_to_quat(rot):
    """ROS quaternion ``(x, y, z, w)`` with w >= 0 of a 3x3 rotation (Shepperd's method)."""
    r = np.asarray(rot, dtype=float)[:3, :3]
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


def inverse(t):
    """Inverse of a rigid 4x4 transform."""
    inv = np.eye(4)
    inv[:3, :3] = t[:3, :3].T
    inv[:3, 3] = -t[:3, :3].T @ t[:3, 3]
    return inv


def wrap_angle(angle):
    """Wrap ``angle`` [rad] into (-pi, pi]."""
    a = math.fmod(angle + math.pi, 2.0 * math.pi)
    if a <= 0.0:
        a += 2.0 * math.pi
    return a - math.pi
