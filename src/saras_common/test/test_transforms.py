"""saras_common.transforms: conventions, round trips, validation, geometry_msgs conversions."""
import math

import numpy as np
import pytest

from saras_common import transforms as tf

RNG = np.random.default_rng(7)


def random_rotation():
    q = RNG.normal(size=4)
    return tf.quaternion_to_matrix(q)


def random_transform():
    return tf.make_transform(random_rotation(), RNG.uniform(-1, 1, 3))


def test_elementary_rotations_follow_the_right_hand_rule():
    np.testing.assert_allclose(tf.rot_z(math.pi / 2)[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(tf.rot_x(math.pi / 2)[:3, :3] @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(tf.rot_y(math.pi / 2)[:3, :3] @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(tf.axis_angle([0, 0, 2], 0.3), tf.rot_z(0.3), atol=1e-15)
    np.testing.assert_allclose(tf.translation(z=2.0)[:3, 3], [0, 0, 2])
    with pytest.raises(ValueError):
        tf.axis_angle([0, 0, 0], 1.0)


def test_rpy_is_fixed_axis_x_then_y_then_z():
    r, p, y = 0.1, -0.4, 2.5
    expected = tf.rot_z(y) @ tf.rot_y(p) @ tf.rot_x(r)
    np.testing.assert_allclose(tf.transform_from_rpy([1, 2, 3], [r, p, y])[:3, :3], expected[:3, :3], atol=1e-15)
    xyz, rpy = tf.rpy_from_transform(tf.transform_from_rpy([1, 2, 3], [r, p, y]))
    np.testing.assert_allclose(xyz, [1, 2, 3])
    np.testing.assert_allclose(rpy, [r, p, y], atol=1e-12)


def test_rpy_at_gimbal_lock_reproduces_the_rotation():
    R = tf.rpy_to_matrix([0.3, math.pi / 2, 0.2])
    np.testing.assert_allclose(tf.rpy_to_matrix(tf.matrix_to_rpy(R)), R, atol=1e-9)


def test_quaternions_are_ros_ordered_with_non_negative_w():
    q = tf.quaternion_from_matrix(tf.rot_z(math.pi / 2))
    np.testing.assert_allclose(q, [0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)], atol=1e-15)
    for _ in range(200):
        R = random_rotation()
        q = tf.quaternion_from_matrix(R)
        assert q[3] >= 0 and abs(np.linalg.norm(q) - 1) < 1e-12
        np.testing.assert_allclose(tf.quaternion_to_matrix(q), R, atol=1e-12)
    # each branch of Shepperd's method (rotations by pi about x, y, z)
    for axis in np.eye(3):
        R = tf.axis_angle(axis, math.pi)[:3, :3]
        np.testing.assert_allclose(tf.quaternion_to_matrix(tf.quaternion_from_matrix(R)), R, atol=1e-12)
    with pytest.raises(ValueError):
        tf.quaternion_to_matrix([0, 0, 0, 0])
    with pytest.raises(ValueError):
        tf.quaternion_to_matrix([0, 0, float('nan'), 1])


def test_inverse_and_points():
    for _ in range(20):
        T = random_transform()
        np.testing.assert_allclose(T @ tf.inverse(T), np.eye(4), atol=1e-12)
    T = tf.transform_from_quaternion([1, 0, 0], tf.quaternion_from_matrix(tf.rot_z(math.pi / 2)))
    np.testing.assert_allclose(tf.transform_points(T, [[1, 0, 0], [0, 0, 1]]), [[1, 1, 0], [1, 0, 1]], atol=1e-12)
    np.testing.assert_allclose(tf.quaternion_from_transform(T), tf.quaternion_from_matrix(T[:3, :3]))


@pytest.mark.parametrize('angle', [0.0, 1e-9, 1e-4, 0.7, math.pi / 2, math.pi - 1e-7, math.pi])
def test_rotation_angle_is_accurate_near_zero_and_pi(angle):
    axis = RNG.normal(size=3)
    R = tf.axis_angle(axis, angle)
    assert abs(tf.rotation_angle(R) - angle) < 1e-8
    assert abs(tf.rotation_angle_deg(R) - math.degrees(angle)) < 1e-6


def test_rotvec_matches_axis_angle_and_is_identity_at_zero():
    w = np.array([0.1, -0.2, 0.3])
    T = tf.transform_from_rotvec(w, [1, 2, 3])
    np.testing.assert_allclose(T[:3, :3], tf.axis_angle(w, np.linalg.norm(w))[:3, :3], atol=1e-15)
    np.testing.assert_allclose(T[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(tf.transform_from_rotvec([0, 0, 0]), np.eye(4))


def test_average_rotation():
    R0 = random_rotation()
    Rs = [R0 @ tf.axis_angle(a, 0.05)[:3, :3] for a in np.eye(3)] + \
         [R0 @ tf.axis_angle(a, -0.05)[:3, :3] for a in np.eye(3)]
    assert tf.rotation_angle(tf.average_rotation(Rs).T @ R0) < 1e-3
    np.testing.assert_allclose(tf.average_rotation([R0, np.eye(3)], [1.0, 0.0]), R0, atol=1e-12)


def test_wrap_angle():
    assert tf.wrap_angle(math.pi) == pytest.approx(math.pi)
    assert tf.wrap_angle(-math.pi) == pytest.approx(math.pi)
    assert tf.wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert tf.wrap_angle(0.25) == pytest.approx(0.25)


def test_validate_transform():
    T = random_transform()
    np.testing.assert_array_equal(tf.validate_transform(T.tolist()), T)
    bad = [np.eye(3), np.diag([1, 1, -1, 1.0]), np.diag([2, 1, 1, 1.0]), np.full((4, 4), np.nan),
           np.vstack([np.eye(4)[:3], [0, 0, 1, 1]]), 'x']
    for B in bad:
        with pytest.raises(tf.NonRigidTransformError, match='ee_pose'):
            tf.validate_transform(B, 'ee_pose')
    assert tf.validate_transforms([T, T], 'poses').shape == (2, 4, 4)
    with pytest.raises(tf.NonRigidTransformError, match=r'poses\[1\]'):
        tf.validate_transforms([T, np.eye(3)], 'poses')
    with pytest.raises(ValueError):
        tf.validate_transforms(None, 'poses')


class _V(object):
    def __init__(self, **kw):
        self.__dict__.update(kw)


def _pose(x, y, z, qx, qy, qz, qw):
    return _V(position=_V(x=x, y=y, z=z), orientation=_V(x=qx, y=qy, z=qz, w=qw))


def test_pose_to_matrix_validates():
    T = tf.pose_to_matrix(_pose(1, 2, 3, 0, 0, 0, 1))
    np.testing.assert_allclose(T, tf.translation(1, 2, 3))
    with pytest.raises(ValueError, match='NaN'):
        tf.pose_to_matrix(_pose(float('nan'), 0, 0, 0, 0, 0, 1))
    with pytest.raises(ValueError, match='norm'):
        tf.pose_to_matrix(_pose(0, 0, 0, 0, 0, 0, 0.5))
    np.testing.assert_allclose(tf.pose_to_matrix(_pose(0, 0, 0, 0, 0, 0, 0.5), norm_tolerance=None), np.eye(4))


def test_in_place_setters_write_xyz_and_quaternion():
    p = tf.set_pose_msg(_pose(0, 0, 0, 0, 0, 0, 1), np.array([1, 2, 3]), (0, 0, 1, 0))
    assert (p.position.x, p.position.y, p.position.z) == (1.0, 2.0, 3.0)
    assert (p.orientation.z, p.orientation.w) == (1.0, 0.0)


def test_geometry_msgs_round_trip():
    pytest.importorskip('geometry_msgs.msg')
    T = random_transform()
    np.testing.assert_allclose(tf.pose_to_matrix(tf.matrix_to_pose(T)), T, atol=1e-12)
    np.testing.assert_allclose(tf.transform_msg_to_matrix(tf.matrix_to_transform_msg(T)), T, atol=1e-12)
    ts = tf.transform_stamped('world', 'tool', T)
    assert ts.header.frame_id == 'world' and ts.child_frame_id == 'tool'
    np.testing.assert_allclose(tf.transform_msg_to_matrix(ts.transform), T, atol=1e-12)
    ts2 = tf.transform_stamped('a', 'b', xyz=[1, 2, 3], q=[0, 0, 0, 1])
    assert ts2.transform.translation.z == 3.0 and ts2.transform.rotation.w == 1.0


def test_rpy_and_quaternions_match_scipy():
    Rotation = pytest.importorskip('scipy.spatial.transform').Rotation
    for _ in range(200):
        rpy = RNG.uniform(-math.pi, math.pi, 3)
        ref = Rotation.from_euler('xyz', rpy)   # extrinsic x, y, z = URDF rpy
        q = tf.quaternion_from_matrix(tf.rpy_to_matrix(rpy))
        assert min(np.abs(q - ref.as_quat()).max(), np.abs(q + ref.as_quat()).max()) < 1e-12
        assert abs(tf.rotation_angle(ref.as_matrix()) - ref.magnitude()) < 1e-9
