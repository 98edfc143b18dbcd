"""URDF joint transforms of saras_arm_tf against the analytic SARAS arm kinematics of
saras_description (independent code: the URDF is composed joint by joint, the reference is the
closed-form RCM pivot kinematics) and against hand-computed single joints."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from saras_drivers import saras_arm_kinematics as sak
from saras_drivers import saras_arm_tf as stf

MAKE_URDF = os.path.join(os.path.dirname(__file__), '..', '..', 'saras_description', 'scripts', 'make_urdf')


def _urdf(side):
    return subprocess.check_output([sys.executable, MAKE_URDF, 'saras_arm', '--prefix', 'mesa_%s/' % side],
                                   universal_newlines=True)


@pytest.mark.parametrize('side', ['left', 'right'])
def test_tool_tip_equals_analytic_kinematics(side):
    kin = sak.load(side)
    prefix = 'mesa_%s/' % side
    tf = stf.UrdfTf(_urdf(side), kin.joint_names(prefix))
    lower = np.array([-0.5, -0.5, 0.05, -1.0, -1.0, 0.0])
    upper = np.array([0.5, 0.5, 0.15, 1.0, 1.0, 0.5])
    rng = np.random.RandomState(3)
    for _ in range(20):
        motors = lower + rng.uniform(size=6) * (upper - lower)
        q = list(kin.pa_joints) + list(motors)
        ref = kin.rcm_in_base().dot(kin.tip_in_rcm(motors))
        got = tf.chain(q, prefix + 'sbs_world', prefix + 'tool_tip')
        np.testing.assert_allclose(got[:3, 3], ref[:3, 3], atol=1e-9)
        # the shaft axis (tool z) agrees; the analytic model's roll convention is the same frame
        np.testing.assert_allclose(got[:3, :3], ref[:3, :3], atol=1e-9)
        rcm = tf.chain(q, prefix + 'sbs_world', prefix + 'rcm')
        np.testing.assert_allclose(rcm, kin.rcm_in_base(), atol=1e-9)


def test_moving_transforms_compose_to_the_chain():
    kin = sak.load('left')
    tf = stf.UrdfTf(_urdf('left'), kin.joint_names('mesa_left/'))
    q = list(kin.pa_joints) + [0.1, -0.2, 0.1, 0.3, -0.4, 0.2]
    frames = {c: (p, x, qu) for p, c, x, qu in tf.moving(q) + tf.fixed()}
    assert len(tf.moving(q)) == 13                      # 7 passive + 6 motor joints
    link, m = 'mesa_left/tool_tip', np.eye(4)
    while link != 'mesa_left/sbs_world':
        p, x, qu = frames[link]
        t = np.eye(4)
        x_, y_, z_, w_ = qu
        t[:3, :3] = [[1 - 2 * (y_ * y_ + z_ * z_), 2 * (x_ * y_ - z_ * w_), 2 * (x_ * z_ + y_ * w_)],
                     [2 * (x_ * y_ + z_ * w_), 1 - 2 * (x_ * x_ + z_ * z_), 2 * (y_ * z_ - x_ * w_)],
                     [2 * (x_ * z_ - y_ * w_), 2 * (y_ * z_ + x_ * w_), 1 - 2 * (x_ * x_ + y_ * y_)]]
        t[:3, 3] = x
        m = t.dot(m)
        link = p
    np.testing.assert_allclose(m, tf.chain(q, 'mesa_left/sbs_world', 'mesa_left/tool_tip'), atol=1e-12)


def test_single_joints_by_hand():
    urdf = """<robot name="r">
      <link name="a"/><link name="b"/><link name="c"/><link name="d"/>
      <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
        <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/><axis xyz="0 0 2"/></joint>
      <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/><axis xyz="1 0 0"/></joint>
      <joint name="j3" type="continuous"><parent link="c"/><child link="d"/><axis xyz="1 0 0"/>
        <mimic joint="j1" multiplier="2" offset="0.1"/></joint>
    </robot>"""
    tf = stf.UrdfTf(urdf, ['j1', 'j2'])
    out = {c: (x, q) for _, c, x, q in tf.moving([0.5, 0.2])}
    # b: origin rotated 90 deg about z, then 0.5 rad about z => 90 deg + 0.5 rad about z
    a = math.pi / 2 + 0.5
    np.testing.assert_allclose(out['b'][0], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(out['b'][1], [0, 0, math.sin(a / 2), math.cos(a / 2)], atol=1e-12)
    np.testing.assert_allclose(out['c'][0], [0.2, 0, 0], atol=1e-12)
    np.testing.assert_allclose(out['d'][1], [math.sin(0.55), 0, 0, math.cos(0.55)], atol=1e-12)


@pytest.mark.parametrize('side', ['left', 'right'])
def test_per_sample_transforms_equal_the_matrix_composition(side):
    """Joint.xyz_quat (plain floats, used per sample by UrdfTf.moving) is the transform of
    Joint.transform (4x4 matrices) for every joint of the arm, the quaternion with w >= 0, over
    the joints' whole range and beyond (angles past +-pi flip the quaternion's sign)."""
    from saras_common.transforms import quaternion_from_matrix
    kin = sak.load(side)
    tf = stf.UrdfTf(_urdf(side), kin.joint_names('mesa_%s/' % side))
    rng = np.random.RandomState(5)
    assert {j.type for j in tf.joints} >= {'revolute', 'prismatic', 'fixed'}
    for j in tf.joints:
        for v in list(rng.uniform(-4.0, 4.0, 25)) + [0.0, math.pi, -math.pi]:
            xyz, quat = j.xyz_quat(v)
            m = j.transform(v)
            np.testing.assert_allclose(xyz, m[:3, 3], atol=1e-12)
            np.testing.assert_allclose(quat, quaternion_from_matrix(m), atol=1e-12)
            assert quat[3] >= 0.0 and abs(np.linalg.norm(quat) - 1.0) < 1e-12


def test_bad_descriptions_are_clear_errors():
    with pytest.raises(ValueError, match='XML'):
        stf.UrdfTf('<robot', [])
    with pytest.raises(ValueError, match='unsupported'):
        stf.UrdfTf('<robot><joint name="f" type="floating"><parent link="a"/><child link="b"/></joint></robot>', [])
    with pytest.raises(ValueError, match='not in the published'):
        stf.UrdfTf('<robot><joint name="j" type="revolute"><parent link="a"/><child link="b"/>'
                   '<axis xyz="0 0 1"/></joint></robot>', ['k'])


def test_tf_messages_refill_the_preallocated_message():
    """urdf_tf_messages: one TFMessage allocated at start-up, refilled in place per sample with the
    UrdfTf transforms and the given stamp; the fixed joints as a separate list."""
    pytest.importorskip('geometry_msgs.msg')
    from saras_drivers.urdf_tf_messages import UrdfTfMessages
    kin = sak.load('left')
    tf = stf.UrdfTf(_urdf('left'), kin.joint_names('mesa_left/'))
    q0 = list(kin.pa_joints) + [0.0] * 6
    msgs = UrdfTfMessages(tf, q0, 1)
    q = list(kin.pa_joints) + [0.1, -0.2, 0.08, 0.3, -0.1, 0.2]
    first = msgs.moving(q, 7)
    ids = [id(t) for t in first.transforms]
    second = msgs.moving(q, 8)
    assert second is first and [id(t) for t in second.transforms] == ids
    ref = tf.moving(q)
    assert len(second.transforms) == len(ref) > 0
    for t, (parent, child, xyz, quat) in zip(second.transforms, ref):
        assert (t.header.frame_id, t.child_frame_id, t.header.stamp) == (parent, child, 8)
        tr, ro = t.transform.translation, t.transform.rotation
        np.testing.assert_allclose([tr.x, tr.y, tr.z], xyz, atol=0)
        np.testing.assert_allclose([ro.x, ro.y, ro.z, ro.w], quat, atol=0)
    fixed = msgs.static(3)
    assert [(t.header.frame_id, t.child_frame_id) for t in fixed] == [(p, c) for p, c, _, _ in tf.fixed()]


def test_tf_rate_limiter_keeps_the_rate_on_a_grid():
    """urdf_tf_messages.RateLimiter (robot_state_publisher's publish_frequency): 50 Hz out of a
    jittery 300 Hz stream on average and never two broadcasts closer than the sample spacing
    allows (grid +- one sample spacing and the jitter); every second sample of an exact 100 Hz stream; every sample at rate 0; after a gap or
    a clock jump the next sample is broadcast at once."""
    from saras_drivers.urdf_tf_messages import RateLimiter
    rng = np.random.default_rng(3)
    lim = RateLimiter(50.0)
    t = np.arange(3000) / 300.0 + rng.uniform(-1e-3, 1e-3, 3000)   # 10 s at 300 Hz, +-1 ms
    sent = [x for x in t if lim.due(x)]
    assert abs(len(sent) - 500) <= 1
    gaps = np.diff(sent)
    assert gaps.min() > 0.02 - 1.0 / 300 - 2e-3 and gaps.max() < 0.02 + 1.0 / 300 + 2e-3
    lim = RateLimiter(50)
    flags = [lim.due(k / 100.0) for k in range(100)]
    assert flags == [k % 2 == 0 for k in range(100)]
    lim = RateLimiter(0.0)
    assert all(lim.due(k * 1e-4) for k in range(50))
    lim = RateLimiter(50.0)
    assert lim.due(1.0) and not lim.due(1.005)
    assert lim.due(3.0)                   # gap of 2 s
    assert lim.due(2.5)                   # clock jumped back
    assert not lim.due(2.51) and lim.due(2.52)
    for bad in (-1.0, float('nan'), float('inf'), True, 'fast', None):
        with pytest.raises(ValueError):
            RateLimiter(bad)
