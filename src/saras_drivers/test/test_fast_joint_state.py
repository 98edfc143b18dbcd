"""saras_drivers.fast_joint_state: the bytes of sensor_msgs/JointState's generated serialize, with
the names and frame cached (and rebuilt when they change)."""
import io

import pytest

pytest.importorskip('sensor_msgs.msg')
import genpy  # noqa: E402
import rospy  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from saras_drivers.fast_joint_state import FastJointState  # noqa: E402


def _bytes(msg):
    b = io.BytesIO()
    msg.serialize(b)
    return b.getvalue()


def _pair(**fields):
    return FastJointState(**fields), JointState(**fields)


def _same(fast, ref):
    assert _bytes(fast) == _bytes(ref)
    back = JointState()
    back.deserialize(_bytes(fast))
    assert back == ref


def test_same_bytes_as_the_generated_code_while_fields_change():
    names = ['mesa_left/pa_%d' % k for k in range(7)] + ['mesa_left/er_yaw', 'mesa_left/jaw']
    fast, ref = _pair(name=names, position=[0.1 * k for k in range(9)])
    for k in range(5):                     # the same joint list, new stamps and positions
        for m in (fast, ref):
            m.header.seq, m.header.stamp = k, rospy.Time(1700000000 + k, 123456789 * k % 10 ** 9)
            m.position = [0.5 * k - j * 1e-3 for j in range(9)]
        _same(fast, ref)
    for m in (fast, ref):                  # the names, the frame, the joint count change
        m.name = names[:3] + ['jaw_\u00e9']
        m.position = [1.0, 2.0, 3.0, -4.0]
        m.header.frame_id = 'mesa_left/sbs_world'
    _same(fast, ref)
    for m in (fast, ref):
        m.name[0] = 'renamed'              # changed in place
    _same(fast, ref)
    for m in (fast, ref):                  # velocities and efforts: the generated code
        m.velocity, m.effort = [0.0] * 4, [1.0] * 4
    _same(fast, ref)
    for m in (fast, ref):
        m.velocity, m.effort, m.name, m.position = [], [], [], []
    _same(fast, ref)


def test_bad_field_is_a_serialization_error():
    fast = FastJointState(name=['a'], position=['not a number'])
    with pytest.raises(genpy.SerializationError):
        _bytes(fast)
