"""Rigid-body helpers of the main-surgeon simulators (no ROS imports).

Thin 3x3 / 4x4 adapters over :mod:`saras_common.transforms` (the platform's one
implementation of rotations and quaternions) and :mod:`saras_description.frames` (the one parser of
the frames-YAML format). Conventions: ``T_a_b`` maps coordinates in frame ``b`` to frame ``a``
(``p_a = T_a_b @ p_b``); quaternions are ``(x, y, z, w)`` as in geometry_msgs; metres, radians.
"""
import numpy as np
from saras_description import frames as _frames
from saras_common import transforms as _tf


def rot_x(a):
    """3x3 rotation about x by ``a`` [rad]."""
    return _tf.rot_x(a)[:3, :3]


def rot_y(a):
    """3x3 rotation about y by ``a`` [rad]."""
    return _tf.rot_y(a)[:3, :3]


def rot_z(a):
    """3x3 rotation about z by ``a`` [rad]."""
    return _tf.rot_z(a)[:3, :3]


def rpy_to_matrix(roll, pitch, yaw):
    """Fixed-axis roll (x), then pitch (y), then yaw (z): ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    return _tf.rpy_to_matrix((roll, pitch, yaw))


def make_transform(R=None, t=None):
    """4x4 homogeneous transform from a 3x3 rotation and a translation [m]."""
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if t is not None:
        T[:3, 3] = t
    return T


#: Inverse of a rigid 4x4 transform.
invert = _tf.inverse
#: Unit quaternion ``(x, y, z, w)`` (w >= 0) of a 3x3 rotation matrix.
quaternion_from_matrix = _tf.quaternion_from_matrix
#: 3x3 rotation matrix of a quaternion ``(x, y, z, w)`` (normalised).
matrix_from_quaternion = _tf.quaternion_to_matrix


def transform_from_pose(xyz, quat):
    """4x4 transform from a translation [m] and a quaternion ``(x, y, z, w)``."""
    return make_transform(matrix_from_quaternion(quat), xyz)


def load_frames_file(path):
    """Read a world_frames YAML (saras_bringup format) into ``{child: (parent, T_parent_child)}``.

    Raises ``ValueError`` (:class:`saras_description.frames.FramesError`) naming the offending entry.
    """
    return _frames.frames_by_child(_frames.load_frames(path, root=None))
