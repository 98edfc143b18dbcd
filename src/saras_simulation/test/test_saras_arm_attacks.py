"""Attacks on the SARAS arm Socket.IO link, against the simulator server over real sockets (no ROS).

Each attack: the simulated arm does not move (its joints stay where they are), the attack is counted
in the counters the simulator reports on /diagnostics (SessionGate.counters(), server.rejected), and
the legitimate, authenticated commander keeps control at its rate.
"""
import json
import multiprocessing
import time

import engineio
import numpy as np
import pytest
import socketio

from saras_drivers import saras_arm_auth as auth
from saras_drivers import saras_arm_kinematics as sak
from saras_drivers import saras_arm_protocol as proto
from saras_drivers.saras_arm_client import SarasArmClient
from saras_simulation.saras_arm_model import SarasArmModel
from saras_simulation.saras_arm_server import SarasArmServer

from arm_link_support import ARM, KEY, PA
from arm_link_support import free_port as _free_port
from arm_link_support import wait_until as _wait


@pytest.fixture
def arm():
    model = SarasArmModel(sak.load('left', PA), max_velocity=2.0)
    port = _free_port()
    server = SarasArmServer(model, port=port, rate=500.0, state_rate=100.0, key=KEY, arm=ARM)
    server.start_in_thread()
    url = 'http://127.0.0.1:%d' % port
    yield model, server, url
    server.stop()


def _target(model, dq=(0.1, -0.1, 0.02)):
    q = model.q.copy()
    q[:3] += dq
    return [float(x) for x in model.tip_in_base(q)[:3, 3]]


def _still(model, q0):
    return np.allclose(model.q, q0, atol=1e-12) and np.allclose(model.target, q0, atol=1e-12)


def _raw(url):
    """An Engine.IO connection that speaks Socket.IO packets by hand (no client-side checks)."""
    eio = engineio.Client()
    eio.connect(url, transports=['websocket'], engineio_path='socket.io')
    return eio


def test_unauthenticated_client_sending_set_target_never_moves_the_arm(arm):
    model, server, url = arm
    q0 = model.q.copy()
    goal = _target(model)
    eio = _raw(url)
    eio.send('0')                                               # CONNECT without auth
    for k in range(50):
        try:
            eio.send('42' + json.dumps(['set_target', proto.make_set_target(k, goal)]))
        except Exception:  # pylint: disable=broad-except
            break                                               # transport closed by the server
    time.sleep(0.5)
    eio.disconnect()
    assert server.gate.refused['missing'] == 1
    assert _still(model, q0) and server.accepted == 0
    # the library client without auth is refused before any event
    sio = socketio.Client(reconnection=False)
    with pytest.raises(socketio.exceptions.ConnectionError):
        sio.connect(url, transports=['websocket'], wait_timeout=2)
    assert server.gate.refused['missing'] == 2


@pytest.mark.parametrize('payload,reason', [
    (lambda: auth.make_auth(bytes(32), ARM, 'command'), 'mac'),                 # wrong key (token)
    (lambda: auth.make_auth(KEY, 'mesa_right', 'command'), 'arm'),              # the other arm's
    (lambda: auth.make_auth(KEY, ARM, 'command', now=time.time() - 120.0), 'expired'),
    (lambda: dict(auth.make_auth(KEY, ARM, 'command'), role='admin'), 'malformed'),
    (lambda: 'token', 'malformed'),
])
def test_wrong_credentials_refused_and_counted(arm, payload, reason):
    model, server, url = arm
    q0 = model.q.copy()
    sio = socketio.Client(reconnection=False)
    with pytest.raises(socketio.exceptions.ConnectionError):
        sio.connect(url, transports=['websocket'], wait_timeout=2, auth=payload())
    assert server.gate.refused[reason] == 1
    assert _still(model, q0)


def test_replayed_auth_payload_refused(arm):
    model, server, url = arm
    captured = auth.make_auth(KEY, ARM, 'command')
    first = socketio.Client(reconnection=False)
    first.connect(url, transports=['websocket'], wait_timeout=2, auth=captured)
    first.disconnect()
    second = socketio.Client(reconnection=False)
    with pytest.raises(socketio.exceptions.ConnectionError):
        second.connect(url, transports=['websocket'], wait_timeout=2, auth=captured)
    assert server.gate.refused['replayed'] == 1


def test_second_and_stale_sessions_never_move_the_arm(arm):
    model, server, url = arm
    q0 = model.q.copy()
    goal = _target(model)
    monitor = socketio.Client(reconnection=False)
    monitor.connect(url, transports=['websocket'], wait_timeout=2, auth=auth.make_auth(KEY, ARM, 'monitor'))
    r = monitor.call(proto.EV_SET_TARGET, proto.make_set_target(1, goal), timeout=2.0)
    assert not r['ok'] and r['code'] == proto.NOT_COMMANDER
    old = socketio.Client(reconnection=False)
    old.connect(url, transports=['websocket'], wait_timeout=2, auth=auth.make_auth(KEY, ARM, 'command'))
    new = socketio.Client(reconnection=False)
    new.connect(url, transports=['websocket'], wait_timeout=2, auth=auth.make_auth(KEY, ARM, 'command'))
    assert _wait(lambda: not old.connected, 2.0)               # superseded: dropped by the server
    assert server.gate.superseded == 1
    assert server.gate.not_commander == 1 and _still(model, q0)
    r = new.call(proto.EV_SET_TARGET, proto.make_set_target(2, goal), timeout=2.0)
    assert r['ok']                                              # the current session commands
    monitor.disconnect()
    new.disconnect()


@pytest.mark.parametrize('payload', [
    {'id': 1, 'position': [0.0, 0.0, 0.1], 'orientation': None, 'evil': 1},    # unknown field
    {'id': 1, 'position': [float('nan'), 0.0, 0.1]},
    {'id': 1, 'position': [0.0, 0.0]},
    {'id': 2 ** 70, 'position': [0.0, 0.0, 0.1]},
    {'id': 1, 'position': 'x' * 1000},
    [1, 2, 3],
])
def test_invalid_payloads_refused(arm, payload):
    model, server, url = arm
    q0 = model.q.copy()
    sio = socketio.Client(reconnection=False)
    sio.connect(url, transports=['websocket'], wait_timeout=2, auth=auth.make_auth(KEY, ARM, 'command'))
    r = sio.call(proto.EV_SET_TARGET, payload, timeout=2.0)
    assert not r['ok'] and r['code'] == proto.BAD_PAYLOAD
    assert server.rejected == 1 and _still(model, q0)
    sio.disconnect()


def test_malformed_json_and_huge_payload_never_move_the_arm(arm):
    model, server, url = arm
    q0 = model.q.copy()
    sio = socketio.Client(reconnection=False)
    sio.connect(url, transports=['websocket'], wait_timeout=2, auth=auth.make_auth(KEY, ARM, 'command'))
    eio = sio.eio
    eio.send('42["set_target",{"id":1,"position":[0,0,')      # malformed JSON
    time.sleep(0.3)
    if sio.connected:
        sio.emit(proto.EV_SET_TARGET, {'id': 2, 'position': [0.0, 0.0, 0.1], 'pad': 'x' * 200000})
    assert _wait(lambda: not sio.connected, 3.0), 'a 200 kB message did not close the connection'
    assert _still(model, q0) and server.accepted == 0


def _flood(url, seconds, role, sent):
    """Another process: an authenticated session emitting set_target at 10 000 events/s."""
    sio = socketio.Client(reconnection=False)
    sio.connect(url, transports=['websocket'], wait_timeout=5, auth=auth.make_auth(KEY, ARM, role))
    n, t0 = 0, time.monotonic()
    while time.monotonic() - t0 < seconds and sio.connected:
        try:
            sio.emit(proto.EV_SET_TARGET, {'id': n, 'position': [0.0, 0.0, 0.1]})
        except Exception:  # pylint: disable=broad-except
            break                                               # dropped by the server
        n += 1
        lag = t0 + n * 1e-4 - time.monotonic()
        if lag > 0:
            time.sleep(lag)
    sent.value = n
    if sio.connected:
        sio.disconnect()


def test_flood_of_10000_events_per_second_is_dropped_and_commander_keeps_control(arm):
    model, server, url = arm
    commander = SarasArmClient(url, KEY, ARM, hold_on_connect=False, role='command')
    commander.start()
    assert commander.wait_connected(5.0)
    sent = multiprocessing.Value('l', 0)
    attacker = multiprocessing.Process(target=_flood, args=(url, 3.0, 'monitor', sent), daemon=True)
    attacker.start()
    goal = _target(model, (0.05, -0.05, 0.01))
    acks, t0 = [], time.monotonic()
    for k in range(100):                                        # the operator at 50 Hz for 2 s
        acks.append(commander.call(proto.EV_SET_TARGET, proto.make_set_target(commander.next_id(), goal,
                                                                               t=time.time()), timeout=1.0))
        time.sleep(max(0.0, t0 + (k + 1) * 0.02 - time.monotonic()))
    elapsed = time.monotonic() - t0
    attacker.join(10.0)
    g = server.gate
    assert g.floods == 1, g.counters()                          # the flooding session was dropped
    assert g.rate_limited >= g.flood_limit
    assert sum(a['ok'] for a in acks) >= 95, [a for a in acks if not a['ok']][:3]
    assert elapsed < 4.0, 'the commander was slowed down to %.1f s for 100 commands' % elapsed
    assert _wait(lambda: np.linalg.norm(model.tip_in_base(model.q)[:3, 3] - goal) < 1e-4, 5.0)
    assert server.events.get('set_target', 0) == sum(a['ok'] for a in acks)   # only the commander's moved it
    commander.stop()
