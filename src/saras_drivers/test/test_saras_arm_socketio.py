"""Simulator server and client over a real Socket.IO connection on 127.0.0.1 (no ROS)."""
import socket
import time

import numpy as np
import pytest

from saras_drivers import saras_arm_kinematics as sak
from saras_drivers import saras_arm_protocol as proto
from saras_drivers.saras_arm_client import NotConnected, SarasArmClient
from saras_drivers.saras_arm_model import SarasArmModel
from saras_drivers.saras_arm_server import SarasArmServer

#: A Positioning-Arm set-up pose [rad] (independent of saras_description's YAML).
PA = [0.0, 0.5, 0.0, 1.3, 0.0, 1.0, 0.0]


def _free_port():
    s = socket.socket()
    s.bind(('127.0.0.1', 0))
    port = s.getsockname()[1]
    s.close()
    return port


def _wait(pred, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


@pytest.fixture
def link():
    model = SarasArmModel(sak.load('left', PA), max_velocity=2.0)
    port = _free_port()
    server = SarasArmServer(model, port=port, rate=500.0, state_rate=250.0)
    server.start_in_thread()
    states, errors = [], []
    client = SarasArmClient('http://127.0.0.1:%d' % port, on_state=states.append,
                            on_error=errors.append, subscribe_state=True, backoff_initial=0.05,
                            backoff_max=0.2)
    client.start()
    assert client.wait_connected(5.0)
    yield server, model, client, states, errors
    client.stop()
    server.stop()


def test_target_reached_and_state_stream(link):
    server, model, client, states, errors = link
    target_q = model.q.copy()
    target_q[:3] += (0.1, -0.1, 0.02)
    goal = model.tip_in_base(target_q)[:3, 3]
    assert client.send_target(goal)
    assert _wait(lambda: states and not states[-1]['moving'] and
                 np.linalg.norm(np.array(states[-1]['ee_position']) - goal) < 1e-6, 5.0)
    n0, t0 = len(states), time.monotonic()
    time.sleep(0.5)
    rate = (len(states) - n0) / (time.monotonic() - t0)
    assert rate > 150.0                                 # nominal 250 Hz (margin for a loaded CI machine)
    assert client.info['joints'] == list(proto.MOTOR_JOINTS)
    assert not errors


def test_rejection_answers_error_and_does_not_move(link):
    server, model, client, states, errors = link
    q0 = model.q.copy()
    bad = model.rcm_position() + np.array([0.0, 0.0, 0.05])   # above the trocar (z up in sbs_world)
    r = client.call(proto.EV_SET_TARGET, proto.make_set_target(77, bad))
    assert not r['ok'] and r['code'] == proto.RCM_VIOLATION and r['id'] == 77
    assert _wait(lambda: errors, 2.0) and errors[0]['code'] == proto.RCM_VIOLATION
    r = client.call(proto.EV_SET_TARGET, {'id': 78, 'position': 'garbage'})
    assert r['code'] == proto.BAD_PAYLOAD
    time.sleep(0.1)
    assert np.array_equal(model.q, q0) and server.rejected == 2


def test_commander_disconnect_holds_and_client_reconnects(link):
    server, model, client, states, errors = link
    model.set_max_velocity(0.2)
    far = model.q.copy()
    far[:2] += 0.3
    assert client.send_target(model.tip_in_base(far)[:3, 3])
    assert _wait(lambda: model.moving, 2.0)
    client.sio.disconnect()                             # simulate a dropped link
    assert _wait(lambda: not model.moving, 2.0)         # server held on its own
    held = model.q.copy()
    assert _wait(lambda: client.connections == 2 and client.connected, 5.0)  # supervisor reconnected
    time.sleep(0.2)
    assert np.allclose(model.q, held) and not model.moving  # nothing replayed


def test_commands_refused_while_disconnected():
    client = SarasArmClient('http://127.0.0.1:%d' % _free_port(), backoff_initial=0.05, backoff_max=0.1)
    client.start()
    try:
        assert not client.send_target((0, 0, 0))
        with pytest.raises(NotConnected):
            client.call(proto.EV_HOLD, {'id': 1})
    finally:
        client.stop()
