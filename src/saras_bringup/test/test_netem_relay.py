"""The impairment relay over loopback: UDP loss/delay/reordering/replies/source address, TCP echo.

Hard properties are asserted exactly (no datagram leaves before its delay, a TCP stream arrives
intact); rates within binomial bounds of the relay's own arrivals; upper bounds on delays are
loose because a busy 2-core machine stalls the relay now and then.
"""
import math
import os
import socket
import struct
import threading
import time

import pytest

from saras_bringup.netem import RelayThread, parse_links

PACKET = struct.Struct('!Id')  # sequence number, send time (time.monotonic) [s]


def udp_link(target, **impairment):
    spec = {'name': 'u', 'protocol': 'udp', 'listen': '127.0.0.1:0',
            'target': '%s:%d' % target, 'seed': 3}
    spec.update(impairment)
    return parse_links({'links': [spec]})


class UdpSink:
    """Receives datagrams in a thread; records (seq, one-way delay [s], sender address)."""

    def __init__(self):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 * 1024 * 1024)
        self.sock.bind(('127.0.0.1', 0))
        self.sock.settimeout(0.2)
        self.address = self.sock.getsockname()
        self.received = []
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        while not self._stop:
            try:
                data, sender = self.sock.recvfrom(2048)
            except socket.timeout:
                continue
            seq, sent = PACKET.unpack_from(data)
            self.received.append((seq, time.monotonic() - sent, sender))

    def close(self):
        self._stop = True
        self._thread.join(5)
        self.sock.close()


@pytest.fixture
def sink():
    s = UdpSink()
    yield s
    s.close()


def send_paced(address, count, per_batch, pause_s, source=None):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    if source:
        sock.bind(source)
    for seq in range(count):
        sock.sendto(PACKET.pack(seq, time.monotonic()), address)
        if seq % per_batch == per_batch - 1:
            time.sleep(pause_s)
    sock.close()


def wait_for(predicate, timeout_s=20.0):
    deadline = time.monotonic() + timeout_s
    while not predicate() and time.monotonic() < deadline:
        time.sleep(0.05)
    return predicate()


def settled(relay, sink):
    """The forward counters once every arrival has left the relay and reached the sink."""
    def done():
        fwd = relay.stats()['u']['forward']
        return (fwd['sent'] + fwd['dropped'] == fwd['received']
                and len(sink.received) >= fwd['sent'])
    previous = None
    for _ in range(40):  # settled: done, and no arrival within 0.3 s
        assert wait_for(done), relay.stats()
        fwd = relay.stats()['u']['forward']
        if previous == fwd['received']:
            return fwd
        previous = fwd['received']
        time.sleep(0.3)
    raise AssertionError('the relay never settled: %s' % relay.stats())


def reorderings(seqs):
    highest, count = -1, 0
    for s in seqs:
        if s < highest:
            count += 1
        highest = max(highest, s)
    return count


def test_udp_random_loss_and_delay(sink):
    n, p, delay = 20000, 0.10, 0.020
    with RelayThread(udp_link(sink.address, delay_ms=20, loss=p)) as relay:
        send_paced(relay.addresses()['u'], n, per_batch=50, pause_s=0.005)
        fwd = settled(relay, sink)
    arrived = fwd['received']
    assert arrived >= 0.99 * n, 'the kernel dropped datagrams before the relay'
    sd = math.sqrt(arrived * p * (1 - p))
    assert abs(fwd['dropped'] - arrived * p) <= 5 * sd
    assert len(sink.received) == fwd['sent']
    delays = sorted(d for _, d, _ in sink.received)
    assert delays[0] >= delay, 'a datagram left before its delay'
    assert fwd['delay_min_ms'] >= 20.0
    assert delays[len(delays) // 2] < delay + 0.080
    assert fwd['reordered'] == 0 and reorderings([s for s, _, _ in sink.received]) == 0


def test_udp_bursty_loss_rate(sink):
    burst = {'p_good_bad': 0.02, 'p_bad_good': 0.25, 'loss_good': 0.0, 'loss_bad': 1.0}
    with RelayThread(udp_link(sink.address, burst=burst)) as relay:
        send_paced(relay.addresses()['u'], 10000, per_batch=50, pause_s=0.005)
        fwd = settled(relay, sink)
    expected = 0.02 / 0.27
    assert fwd['dropped'] / fwd['received'] == pytest.approx(expected, rel=0.3)
    seqs = {s for s, _, _ in sink.received}
    lost = [s not in seqs for s in range(10000)]
    after_loss = sum(1 for a, b in zip(lost, lost[1:]) if a and b) / max(1, sum(lost[:-1]))
    assert after_loss > 0.5, 'losses are not bursty'


def test_udp_jitter_reorders_and_counts_it(sink):
    with RelayThread(udp_link(sink.address, delay_ms=10, jitter_ms=5)) as relay:
        send_paced(relay.addresses()['u'], 500, per_batch=1, pause_s=0.001)
        assert wait_for(lambda: len(sink.received) == 500)
        fwd = relay.stats()['u']['forward']
    seen = reorderings([s for s, _, _ in sink.received])
    assert seen > 10
    assert fwd['reordered'] == seen  # loopback keeps the relay's departure order
    assert min(d for _, d, _ in sink.received) >= 0.005


def test_udp_explicit_reordering_without_jitter(sink):
    reorder = {'probability': 0.1, 'gap_ms': 20}
    with RelayThread(udp_link(sink.address, delay_ms=5, reorder=reorder)) as relay:
        send_paced(relay.addresses()['u'], 1000, per_batch=1, pause_s=0.001)
        assert wait_for(lambda: len(sink.received) == 1000)
        fwd = relay.stats()['u']['forward']
    held = sum(1 for _, d, _ in sink.received if d >= 0.025)
    assert 40 <= held <= 180  # binomial(1000, 0.1): 100 +- 5 sigma (47)
    assert reorderings([s for s, _, _ in sink.received]) > 0 and fwd['reordered'] > 0


def test_udp_source_address_and_reply_path():
    echo = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    echo.bind(('127.0.0.1', 0))
    links = udp_link(echo.getsockname(), delay_ms=15, source='127.0.0.2:0',
                     reverse={'delay_ms': 25})
    with RelayThread(links) as relay:
        client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        client.settimeout(5)
        start = time.monotonic()
        client.sendto(b'ping', relay.addresses()['u'])
        echo.settimeout(5)
        data, sender = echo.recvfrom(100)
        echo.sendto(b'pong:' + data, sender)
        reply, _ = client.recvfrom(100)
        rtt = time.monotonic() - start
        rev = relay.stats()['u']['reverse']
    client.close()
    echo.close()
    assert sender[0] == '127.0.0.2', 'the relay did not send from the configured source'
    assert reply == b'pong:ping' and rtt >= 0.040
    assert rev['sent'] == 1 and rev['delay_min_ms'] >= 25.0


def echo_server():
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.bind(('127.0.0.1', 0))
    server.listen(1)

    def serve():
        conn, _ = server.accept()
        while True:
            data = conn.recv(65536)
            if not data:
                break
            conn.sendall(data)
        conn.close()
        server.close()
    threading.Thread(target=serve, daemon=True).start()
    return server.getsockname()


def test_tcp_echo_intact_and_delayed():
    target = echo_server()
    links = parse_links({'links': [{
        'name': 't', 'protocol': 'tcp', 'listen': '127.0.0.1:0', 'target': '%s:%d' % target,
        'delay_ms': 30, 'jitter_ms': 10, 'reverse': {'delay_ms': 20}, 'seed': 5}]})
    payload = os.urandom(1 << 20)
    with RelayThread(links) as relay:
        conn = socket.create_connection(relay.addresses()['t'], timeout=10)
        start = time.monotonic()
        conn.sendall(payload[:1])
        first = conn.recv(1)
        rtt = time.monotonic() - start
        sender = threading.Thread(target=lambda: (conn.sendall(payload[1:]),
                                                  conn.shutdown(socket.SHUT_WR)))
        sender.start()
        chunks = [first]
        while True:
            data = conn.recv(65536)
            if not data:
                break
            chunks.append(data)
        sender.join(10)
        conn.close()
        stats = relay.stats()['t']
    assert b''.join(chunks) == payload, 'the stream was altered'
    assert rtt >= 0.040  # forward 30 +- 10 ms, reverse 20 ms
    assert stats['forward']['bytes_sent'] == len(payload)
    assert stats['forward']['delay_min_ms'] >= 20.0 and stats['reverse']['delay_min_ms'] >= 20.0
    assert stats['forward']['reordered'] == 0 and stats['forward']['dropped'] == 0
