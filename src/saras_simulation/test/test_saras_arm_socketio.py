"""Simulator server and client over a real Socket.IO connection on 127.0.0.1 (no ROS)."""
import threading
import time

import numpy as np
import pytest

from saras_drivers import saras_arm_kinematics as sak
from saras_drivers import saras_arm_auth as auth
from saras_drivers import saras_arm_protocol as proto
from saras_drivers.saras_arm_client import NotConnected, SarasArmClient
from saras_simulation.saras_arm_model import SarasArmModel
from saras_simulation.saras_arm_server import SarasArmServer

from arm_link_support import ARM, KEY, PA
from arm_link_support import free_port as _free_port
from arm_link_support import wait_until as _wait


@pytest.fixture
def link():
    model = SarasArmModel(sak.load('left', PA), max_velocity=2.0)
    port = _free_port()
    server = SarasArmServer(model, port=port, rate=500.0, state_rate=250.0, key=KEY)
    server.start_in_thread()
    states, errors = [], []
    client = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, on_state=states.append,
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
    client = SarasArmClient('http://127.0.0.1:%d' % _free_port(), KEY, ARM, backoff_initial=0.05, backoff_max=0.1)
    client.start()
    try:
        assert not client.send_target((0, 0, 0))
        with pytest.raises(NotConnected):
            client.call(proto.EV_HOLD, {'id': 1})
    finally:
        client.stop()


# ---------------------------------------------------------------------------- streaming under load
def _stream(state_rate=250.0, **server_kw):
    model = SarasArmModel(sak.load('left', PA), max_velocity=2.0)
    port = _free_port()
    server = SarasArmServer(model, port=port, rate=500.0, state_rate=state_rate, **server_kw, key=KEY)
    server.start_in_thread()
    return model, server, port


def _stall_server(server, seconds):
    """Block the server's event loop (a descheduled or busy simulator process)."""
    server._loop.call_soon_threadsafe(time.sleep, seconds)     # pylint: disable=protected-access


def test_states_in_order_from_one_thread_without_gaps():
    model, server, port = _stream()
    seen = []
    client = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, subscribe_state=True, hold_on_connect=False, role='monitor',
                            on_state=lambda s: seen.append((threading.get_ident(), s['seq'], s['time'])))
    client.start()
    try:
        assert client.wait_connected(5.0)
        assert _wait(lambda: len(seen) > 150, 5.0)
    finally:
        client.stop()
        server.stop()
    threads = set(t for t, _, _ in seen)
    assert len(threads) == 1                           # one dispatcher, not a thread per message
    seqs = [s for _, s, _ in seen]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))   # in order, none lost (fast consumer)
    assert client.conflated == 0 and client.bad_states == 0
    # every sample sits on the 250 Hz grid (catch-up keeps exact sample instants)
    dt = np.diff([t for _, _, t in seen])
    assert np.allclose(dt, 1.0 / 250.0, atol=1e-6), (dt.min(), dt.max(), server.missed)


def test_server_stall_keeps_rate_and_sample_times():
    # a 60 ms stall of the simulator (15 periods at 250 Hz): every missed sample is still sent,
    # integrated to and stamped with its own instant
    model, server, port = _stream(max_catch_up=50)
    seen = []
    client = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, subscribe_state=True, hold_on_connect=False, role='monitor',
                            on_state=seen.append)
    client.start()
    try:
        assert client.wait_connected(5.0)
        far = model.q.copy()
        far[:2] += 0.3
        assert client.send_target(model.tip_in_base(far)[:3, 3])   # moving: samples differ
        assert _wait(lambda: len(seen) > 20, 5.0)
        n0 = len(seen)
        _stall_server(server, 0.06)
        for k in range(5):             # commands queued during the stall: they must not make
            near = model.q.copy()      # the owed samples collapse onto their arrival time
            near[:2] += 0.2 + 0.01 * k
            client.send_target(model.tip_in_base(near)[:3, 3])
            time.sleep(0.005)
        assert _wait(lambda: len(seen) > n0 + 40, 5.0)
    finally:
        client.stop()
        server.stop()
    times = np.array([s['time'] for s in seen[n0 - 5:]])
    assert server.missed == 0
    d = np.diff(times)
    assert np.allclose(d, 1.0 / 250.0, atol=1e-6), [(i, 1e3 * x) for i, x in enumerate(d)
                                                     if abs(x - 0.004) > 1e-6]
    # the joints of each sample are the model integrated to that instant: motion is continuous
    # (per-sample joint change never exceeds what the velocity limit allows in one period)
    q = np.array([s['joints'] for s in seen[n0 - 5:]])
    assert np.all(np.abs(np.diff(q[:, :2], axis=0)) <= 2.0 / 250.0 + 1e-9)


def test_overloaded_server_grid_stays_on_real_time():
    # every state emission costs 4 ms of the server's loop (a simulator starved of CPU: it cannot
    # emit 300 states/s) while set-points arrive at 250 Hz: samples are lost and counted, but the
    # grid and so the sample times stay on real time (not seconds behind). Bounds hold on an idle
    # or a busy machine; how many set-points go stale is load-dependent (bench/saras_arm_rtt.py).
    model, server, port = _stream(state_rate=300.0, max_target_age=0.1)
    emit_state = server._emit_state     # one state sample to the subscribers (here one reader)

    async def slow_emit_state():
        time.sleep(0.004)
        await emit_state()
    server._emit_state = slow_emit_state
    got = []
    reader = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, subscribe_state=True, hold_on_connect=False, role='monitor',
                            on_state=lambda s: got.append((time.time(), s['time'])))
    commander = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, hold_on_connect=False)
    reader.start()
    commander.start()
    try:
        assert reader.wait_connected(5.0) and commander.wait_connected(5.0)
        q0 = model.q.copy()
        t0 = time.time()
        k = 0
        while time.time() < t0 + 4.0:
            near = q0.copy()
            near[:2] += 0.05 * np.sin(0.5 * k / 250.0)
            commander.send_target(model.tip_in_base(near)[:3, 3])
            k += 1
            time.sleep(0.004)
        behind = server.grid_behind()
    finally:
        commander.stop()
        reader.stop()
        server.stop()
    ages = [now - t for now, t in got if now > t0 + 3.0]
    assert ages and max(ages) < 1.0, max(ages)            # sample times on real time
    assert behind < 0.5, behind
    # at most 250 emissions/s against a 300 Hz grid for 4 s: at least 200 samples lost, counted
    assert server.missed > 100
    assert server.accepted > 0                            # set-points still executed
    assert server.accepted + server.stale_targets <= k    # each one executed or dropped, once


def test_stale_set_point_is_counted_and_not_executed():
    # a set_target stamped 1 s ago (max_target_age 0.1 s) is dropped and counted; a fresh one runs
    model, server, port = _stream(max_target_age=0.1)
    commander = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, hold_on_connect=False)
    commander.start()
    try:
        assert commander.wait_connected(5.0)
        q0 = model.q.copy()
        far = q0.copy()
        far[:2] += 0.2
        goal = model.tip_in_base(far)[:3, 3]
        commander.emit(proto.EV_SET_TARGET, proto.make_set_target(commander.next_id(), goal, None,
                                                                  time.time() - 1.0))
        deadline = time.monotonic() + 5.0
        while server.stale_targets < 1 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert server.stale_targets == 1
        time.sleep(0.3)
        assert np.allclose(model.q, q0)                   # not executed
        commander.send_target(goal)
        deadline = time.monotonic() + 5.0
        while server.accepted < 1 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert server.accepted >= 1 and server.stale_targets == 1
        # the same for the jaw (set_clip with a time): an old jaw command is not executed, a fresh one is
        jaw0 = model.target[5]
        commander.emit(proto.EV_SET_CLIP, proto.make_set_clip(commander.next_id(), jaw0 + 0.3, t=time.time() - 1.0))
        deadline = time.monotonic() + 5.0
        while server.stale_targets < 2 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert server.stale_targets == 2 and model.target[5] == jaw0
        commander.emit(proto.EV_SET_CLIP, proto.make_set_clip(commander.next_id(), jaw0 + 0.3, t=time.time()))
        deadline = time.monotonic() + 5.0
        while model.target[5] == jaw0 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert model.target[5] == pytest.approx(jaw0 + 0.3)
    finally:
        commander.stop()
        server.stop()


def test_slow_consumer_bounded_queue_and_link_kept():
    # a consumer 5x slower than the stream for 2.5 s (> ping_interval + ping_timeout used to be
    # enough to drop the link behind the queued states): the link stays up, the oldest states are
    # dropped and counted, order is kept and the delivered state is never more than
    # state_queue samples old
    model, server, port = _stream(ping_interval=0.2, ping_timeout=1.0)
    seen = []
    lag = []

    def slow(s):
        lag.append(server.state_seq - s['seq'])
        seen.append(s['seq'])
        time.sleep(0.02)

    client = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, subscribe_state=True, hold_on_connect=False, role='monitor',
                            on_state=slow, state_queue=5)
    client.start()
    try:
        assert client.wait_connected(5.0)
        time.sleep(2.5)
        assert client.connected and client.connections == 1 and len(server.sids) == 1
    finally:
        client.stop()
        server.stop()
    assert client.conflated > 100
    assert seen == sorted(seen) and len(set(seen)) == len(seen)
    assert client.received_states - client.conflated - client.states <= 5
    # bounded lag: queue (5) + samples in flight (socket buffers, a loaded host); an unbounded
    # queue would be ~2.5 s * (250 - 50) Hz = 500 samples behind by the end
    assert max(lag[len(lag) // 2:]) <= 30, lag


def _slow_reader(client, seconds):
    """Make the client's websocket reader take ``seconds`` per state event (a reader thread
    starved of CPU): the states then wait in the socket buffers, not in the client's mailbox."""
    handler = client.sio.handlers[proto.NAMESPACE][proto.EV_STATE]

    def slow(payload):
        time.sleep(seconds)
        handler(payload)
    client.sio.handlers[proto.NAMESPACE][proto.EV_STATE] = slow


@pytest.mark.parametrize('window', [30, 0])
def test_slow_reader_state_age_bounded_by_flow_control(window):
    # a reader at <= 100 states/s against a 300 Hz stream for 4 s: with flow control the server
    # keeps <= window states in flight and skips the rest, so the age of a received state stays
    # near window / (read rate) = 0.3 s; without it (window 0: no flow control) the kernel's
    # socket buffers hold a growing backlog
    model, server, port = _stream(state_rate=300.0)
    got = []
    client = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, subscribe_state=True, hold_on_connect=False, role='monitor',
                            state_window=window,
                            on_state=lambda s: got.append((time.time(), time.time() - s['time'], s['seq'])))
    _slow_reader(client, 0.01)
    client.start()
    try:
        assert client.wait_connected(5.0)
        t0 = time.time()
        time.sleep(4.0)
        assert client.connected and client.connections == 1
    finally:
        client.stop()
        server.stop()
    late = [age for t, age, _ in got if t > t0 + 3.0]
    seqs = [q for _, _, q in got]
    assert late and seqs == sorted(seqs) and len(set(seqs)) == len(seqs)
    if window:
        assert max(late) < 0.6, max(late)
        assert server.state_skipped > 300               # the samples beyond the window
        assert server.rejected == 0                     # every state_ack well-formed
    else:
        assert max(late) > 1.0, max(late)
        assert server.state_skipped == 0                # the queue check never saw it


def test_malformed_flow_control_refused_and_counted():
    import socketio
    model, server, port = _stream()
    sio = socketio.Client(reconnection=False)
    seen = []
    sio.on(proto.EV_STATE, seen.append)
    try:
        sio.connect('http://127.0.0.1:%d' % port, transports=['websocket'], wait_timeout=2,
                    auth=auth.make_auth(KEY, ARM, 'monitor'))
        r = sio.call(proto.EV_SUBSCRIBE_STATE, {'window': -2}, timeout=2.0)
        assert not r['ok'] and r['code'] == proto.BAD_PAYLOAD and not server.subscribers
        for bad in ({'received': 'x'}, None, [1], {'received': -1}):
            sio.emit(proto.EV_STATE_ACK, bad)
        r = sio.call(proto.EV_SUBSCRIBE_STATE, {'window': 5}, timeout=2.0)
        assert r['ok']
        assert _wait(lambda: len(seen) >= 5, 2.0)
        time.sleep(0.3)
        assert len(seen) == 5                            # never acked: 5 in flight, then skips
        assert server.rejected == 5 and server.state_skipped > 10
        sio.emit(proto.EV_STATE_ACK, {'received': 5})   # acknowledged: the stream resumes
        assert _wait(lambda: len(seen) >= 10, 2.0)
    finally:
        sio.disconnect()
        server.stop()


def test_server_stall_shorter_than_ping_timeout_keeps_link():
    model, server, port = _stream(ping_interval=0.2, ping_timeout=1.5)
    client = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, backoff_initial=0.05, backoff_max=0.1)
    client.start()
    try:
        assert client.wait_connected(5.0)
        _stall_server(server, 1.0)
        time.sleep(2.0)
        assert client.connected and client.connections == 1
    finally:
        client.stop()
        server.stop()



def test_utf8_check_skipped_but_malformed_text_still_refused(link):
    """The connected client skips websocket-client's pure-Python UTF-8 loop; a text frame with
    malformed UTF-8 is still refused (by bytes.decode in the reader), as it was by the check."""
    import websocket
    from saras_drivers.saras_arm_client import skip_utf8_validation
    _, _, client, states, _ = link
    ws = client.sio.eio.ws
    assert ws.frame_buffer.skip_utf8_validation and ws.cont_frame.skip_utf8_validation
    assert _wait(lambda: len(states) > 10, 5.0)          # states still arrive and parse

    class _Feed:
        """Byte source for a websocket-client frame reader: one masked-less text frame."""
        def __init__(self, payload):
            self.data = bytes([0x81, len(payload)]) + payload

        def __call__(self, n):
            out, self.data = self.data[:n], self.data[n:]
            return out

    bad = b'\xc3\x28 not utf-8'
    sock = websocket.WebSocket()
    assert skip_utf8_validation(sock)
    sock.frame_buffer = websocket._abnf.frame_buffer(_Feed(bad), True)
    frame = sock.frame_buffer.recv_frame()
    frame.validate(sock.frame_buffer.skip_utf8_validation)  # no Python UTF-8 loop, no error here
    sock.cont_frame.add(frame)
    opcode, frame = sock.cont_frame.extract(frame)
    assert opcode == websocket.ABNF.OPCODE_TEXT and frame.data == bad
    with pytest.raises(UnicodeDecodeError):
        frame.data.decode('utf-8')                         # what WebSocket.recv() does with text
    assert not skip_utf8_validation(object())             # not a websocket: left alone


def _queued(server, commands, wait):
    """Run ``commands`` (event, payload) as the server's command tasks while its emission lock is
    held for ``wait`` seconds (a loop busy behind a queue), then let them through; returns replies."""
    import asyncio
    server._admit = lambda sid, command: None                  # pylint: disable=protected-access

    async def scenario():
        server._emit_lock = asyncio.Lock()                     # pylint: disable=protected-access
        server._deadline = time.monotonic() + 1e6              # no state samples owed
        fns = {'set_target': server._set_target, 'set_clip': server._set_clip}  # pylint: disable=protected-access
        async with server._emit_lock:                          # pylint: disable=protected-access
            tasks = [asyncio.ensure_future(server._run('sid', ev, p, fns[ev]))  # pylint: disable=protected-access
                     for ev, p in commands]
            await asyncio.sleep(wait)
        return await asyncio.gather(*tasks)
    return asyncio.run(scenario())


def test_a_backlog_of_set_points_executes_the_newest_once():
    # five set_target tasks queued behind a busy loop: the first to run executes the newest, the
    # four older ones are superseded (not executed one after the other, replaying old motion); no
    # age limit here, so that a stall of a loaded test host cannot make them stale
    model = SarasArmModel(sak.load('left', PA), max_velocity=2.0)
    server = SarasArmServer(model, port=_free_port(), rate=500.0, max_target_age=0.0, key=KEY)
    q0 = model.q.copy()
    goals = []
    for k in range(5):
        near = q0.copy()
        near[:2] += 0.01 * (k + 1)
        goals.append(model.tip_in_base(near)[:3, 3])
    replies = _queued(server, [('set_target', proto.make_set_target(k + 1, g, None, time.time()))
                               for k, g in enumerate(goals)], 0.02)
    assert server.accepted == 1 and server.superseded_targets == 4 and server.stale_targets == 0
    assert model.target_id == 5
    assert [r['code'] for r in replies] == [proto.OK] + [proto.SUPERSEDED] * 4


def test_a_set_point_that_waited_beyond_its_age_is_not_executed():
    # fresh when its task started, 150 ms old when the busy loop gets to it (limit 100 ms): stale,
    # not executed (judged when it started, it was executed 150 ms late)
    model = SarasArmModel(sak.load('left', PA), max_velocity=2.0)
    server = SarasArmServer(model, port=_free_port(), rate=500.0, max_target_age=0.1, key=KEY)
    target0 = model.target.copy()
    far = model.q.copy()
    far[:2] += 0.05
    replies = _queued(server, [('set_target', proto.make_set_target(1, model.tip_in_base(far)[:3, 3], None,
                                                                    time.time())),
                               ('set_clip', proto.make_set_clip(2, model.q[5] + 0.3, t=time.time()))], 0.15)
    assert [r['code'] for r in replies] == [proto.STALE, proto.STALE]
    assert server.stale_targets == 2 and server.accepted == 0
    assert np.array_equal(model.target, target0)
