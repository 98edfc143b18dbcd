"""Socket.IO payload schemas: builders and parsers agree; malformed payloads are refused."""

import pytest

from saras_drivers import saras_arm_protocol as proto


def test_set_target_round_trip_and_normalisation():
    cid, p, q = proto.parse_set_target(proto.make_set_target(4, (0.1, 0.2, 0.3), (0, 0, 0, 1.0005)))
    assert cid == 4 and p == (0.1, 0.2, 0.3) and q == pytest.approx((0, 0, 0, 1))
    assert proto.parse_set_target(proto.make_set_target(5, (0, 0, 0)))[2] is None


@pytest.mark.parametrize('payload', [
    None, [], 'x', {}, {'position': [0, 0]}, {'position': [0, 0, float('nan')]},
    {'position': [0, 0, 'a']}, {'position': [0, 0, True]}, {'id': 'a', 'position': [0, 0, 0]},
    {'position': [0, 0, 0], 'orientation': [0, 0, 0, 2]}, {'position': [0, 0, 0], 'orientation': [0, 0, 1]},
])
def test_bad_set_target(payload):
    with pytest.raises(proto.ProtocolError) as e:
        proto.parse_set_target(payload)
    assert e.value.code == proto.BAD_PAYLOAD


def test_clip_and_velocity():
    assert proto.parse_set_clip(proto.make_set_clip(1, float('nan'), 0.3)) == (1, None, 0.3)
    timed = proto.make_set_clip(3, 0.2, t=12.5)
    assert proto.parse_set_clip(timed) == (3, 0.2, None) and proto.target_time(timed) == 12.5
    with pytest.raises(proto.ProtocolError):
        proto.parse_set_clip({'id': 1, 'jaw': 0.2, 'roll': None, 'time': float('nan')})
    assert proto.parse_set_max_velocity(proto.make_set_max_velocity(2, 0.7)) == (2, 0.7)
    with pytest.raises(proto.ProtocolError):
        proto.parse_set_max_velocity({'id': 1, 'max_velocity': float('inf')})


def test_state_round_trip():
    s = proto.make_state(3, 1.0, range(6), (1, 2, 3), (0, 0, 0, 1), (4, 5, 6), True, 0.5, 9)
    out = proto.parse_state(s)
    assert out['joints'] == tuple(float(i) for i in range(6)) and out['target_id'] == 9
    s['joints'] = s['joints'][:5]
    with pytest.raises(proto.ProtocolError):
        proto.parse_state(s)


def test_flow_control_payloads():
    assert proto.parse_subscribe_state(None) == 0 and proto.parse_subscribe_state({}) == 0
    assert proto.parse_subscribe_state({'window': 30}) == 30
    assert proto.parse_state_ack({'received': 12}) == 12
    for bad in ({'window': -1}, {'window': 2.5}, {'window': True}, {'window': 'a'}, [], 'x'):
        with pytest.raises(proto.ProtocolError) as e:
            proto.parse_subscribe_state(bad)
        assert e.value.code == proto.BAD_PAYLOAD
    for bad in (None, {}, {'received': -3}, {'received': 1.0}, {'received': None}, [1]):
        with pytest.raises(proto.ProtocolError):
            proto.parse_state_ack(bad)


def test_set_target_time():
    p = proto.make_set_target(1, (0, 0, 0), t=123.5)
    assert proto.target_time(p) == 123.5 and proto.parse_set_target(p)[0] == 1
    assert proto.target_time(proto.make_set_target(1, (0, 0, 0))) is None
    for bad in ('x', float('nan'), True, [1.0]):
        p = proto.make_set_target(1, (0, 0, 0))
        p['time'] = bad
        with pytest.raises(proto.ProtocolError):
            proto.parse_set_target(p)
