"""saras_arm_client's Engine.IO writes without a writer thread per packet (no server, no ROS): the
packets queued during the handshake go out first and in order, then every packet is written by the
thread that sends it, in the order of the calls; the end of the connection (None) ends the writer
task and later packets are neither written nor queued for a connection that is gone."""
import threading
import time

from engineio import packet as eio_packet

from saras_drivers.saras_arm_client import _InlineEngineIOClient


class FakeWebSocket(object):
    def __init__(self, fail=False):
        self.sent = []                 # (text, thread name)
        self.fail = fail

    def send(self, data):
        if self.fail:
            raise OSError('broken pipe')
        self.sent.append((data, threading.current_thread().name))


def _client(ws):
    c = _InlineEngineIOClient(logger=False)
    c.state, c.current_transport, c.ws = 'connected', 'websocket', ws
    c.queue = c.create_queue()
    return c


def _wait(cond, timeout=10.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.005)
    return cond()


def _msg(text):
    return eio_packet.Packet(eio_packet.MESSAGE, data=text)


def test_handshake_packets_first_then_written_by_the_sender_in_order():
    ws = FakeWebSocket()
    c = _client(ws)
    for k in range(3):                          # before the writer task runs: queued
        c._send_packet(_msg('early%d' % k))
    assert ws.sent == [] and c.queue.qsize() == 3
    writer = threading.Thread(target=c._write_loop, name='writer')
    writer.start()
    assert _wait(lambda: c._inline)
    assert [d for d, _ in ws.sent] == ['4early0', '4early1', '4early2']
    assert all(t == 'writer' for _, t in ws.sent)

    def send(tag):
        for k in range(200):
            c._send_packet(_msg('%s%d' % (tag, k)))
    senders = [threading.Thread(target=send, args=(tag,), name='sender_' + tag) for tag in 'ab']
    for s in senders:
        s.start()
    for s in senders:
        s.join(10.0)
    late = ws.sent[3:]
    assert len(late) == 400 and c.queue.qsize() == 0
    for tag in 'ab':                            # each sender's packets: its own thread, its order
        mine = [(d, t) for d, t in late if d.startswith('4' + tag)]
        assert [d for d, _ in mine] == ['4%s%d' % (tag, k) for k in range(200)]
        assert {t for _, t in mine} == {'sender_' + tag}

    c.queue.put(None)                           # end of the connection (disconnect, reader gone)
    writer.join(10.0)
    assert not writer.is_alive() and not c._inline
    c.state = 'disconnected'
    c._send_packet(_msg('after'))
    assert len(ws.sent) == 403 and c.queue.qsize() == 0


def test_failed_write_is_logged_not_raised():
    ws = FakeWebSocket(fail=True)
    c = _client(ws)
    writer = threading.Thread(target=c._write_loop, name='writer')
    writer.start()
    assert _wait(lambda: c._inline)
    c._send_packet(_msg('x'))                   # the reader sees the broken link and reconnects
    c.queue.put(None)
    writer.join(10.0)
    assert not writer.is_alive()


def test_emit_text_is_python_socketio_s():
    """_emit_json writes the EVENT text python-socketio's emit writes, for every command payload."""
    import pytest
    import socketio
    from socketio import packet as sio_packet
    from saras_drivers import saras_arm_protocol as proto
    from saras_drivers.saras_arm_client import _emit_json

    class Eio(object):
        def __init__(self):
            self.sent = []

        def send(self, data):
            self.sent.append(data)

    class Sio(object):
        def __init__(self, namespaces):
            self.namespaces, self.eio = namespaces, Eio()

    payloads = [(proto.EV_SET_TARGET, proto.make_set_target(7, (0.1, -0.2, 1e-9), (0.0, 0.0, 0.6, 0.8), 1.7e9 + 0.123)),
                (proto.EV_SET_TARGET, proto.make_set_target(2 ** 40, (1, 2, 3))),
                (proto.EV_SET_CLIP, proto.make_set_clip(8, 0.3, float('nan'), t=12.5)),
                (proto.EV_HOLD, {'id': 9}), (proto.EV_STATE_ACK, {'received': 30}),
                (proto.EV_SET_MAX_VELOCITY, proto.make_set_max_velocity(10, 1.5))]
    sio = Sio({'/': 'sid'})
    for event, payload in payloads:
        _emit_json(sio, event, payload)
        ref = sio_packet.Packet(sio_packet.EVENT, namespace='/', data=[event, payload]).encode()
        assert sio.eio.sent[-1] == ref
    with pytest.raises(socketio.exceptions.BadNamespaceError):
        _emit_json(Sio({}), proto.EV_HOLD, {'id': 1})
