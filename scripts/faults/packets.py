#!/usr/bin/env python3
"""Console-packet faults of the fault suite (scripts/faults/run.sh), ROS-free: hostile datagrams
sent to the Touchball receiver's UDP port on loopback, without the deployment key.

  packets.py capture PORT SECONDS FILE   record the console's state packets to 127.0.0.1:PORT for
                                         SECONDS (AF_PACKET on lo: root) into FILE (length-prefixed)
  packets.py malformed PORT SECONDS RATE FILE    random bytes, short datagrams, wrong magic,
                                         wrong version (1 and 3), wrong type, wrong size and bad
                                         tags (a captured packet with another tag or a changed
                                         field, a packet signed with another key), at RATE pkt/s
  packets.py replay PORT SECONDS RATE FILE       the captured (valid, already accepted) packets
                                         again, in their order, at RATE pkt/s
  packets.py flood PORT SECONDS RATE FILE        replayed and malformed packets interleaved at
                                         RATE pkt/s (run.sh: 10x the console rate)

Each sending command prints one line ``t_start t_end sent`` (wall-clock seconds, datagrams) and
the count per kind on stderr. The protocol is the one of saras_drivers' docs/touchball_protocol.md;
nothing here changes it. Only 127.0.0.1 is ever a target.
"""
import os
import random
import socket
import struct
import sys
import time

from saras_drivers import touchball_protocol as tp
from saras_drivers.touchball_protocol import MAGIC, STATE_SIZE, TYPE_STATE, VERSION
from saras_drivers.touchball_protocol import TAG_SIZE as TAG

SEQ_OFFSET = struct.calcsize('<4sBBH')   # tp.HEADER: magic, version, type, size, then seq (u32)
ETH_P_ALL, PACKET_OUTGOING = 0x0003, 4


def udp_payload(frame, port):
    """The UDP payload of an Ethernet(lo)/IPv4/UDP frame to ``port``, else None."""
    if len(frame) < 14 + 20 + 8 or frame[12:14] != b'\x08\x00':
        return None
    ip = frame[14:]
    ihl = (ip[0] & 0x0F) * 4
    if ip[0] >> 4 != 4 or ip[9] != 17 or len(ip) < ihl + 8:
        return None
    dport, length = struct.unpack_from('!HH', ip, ihl + 2)
    if dport != port:
        return None
    return bytes(ip[ihl + 8:ihl + length])


def capture(port, seconds, limit=100000):
    """State packets (180 bytes, TBAL v2) sent to 127.0.0.1:``port`` during ``seconds``."""
    s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
    s.bind(('lo', 0))
    s.settimeout(0.1)
    got, end = [], time.time() + seconds
    try:
        while time.time() < end and len(got) < limit:
            try:
                frame, addr = s.recvfrom(65535)
            except socket.timeout:
                continue
            if addr[2] == PACKET_OUTGOING:          # lo shows every datagram twice
                continue
            p = udp_payload(frame, port)
            if p and len(p) == STATE_SIZE and p[:4] == MAGIC and p[4] == VERSION and p[5] == TYPE_STATE:
                got.append(p)
    finally:
        s.close()
    return got


def save(packets, path):
    with open(path, 'wb') as f:
        for p in packets:
            f.write(struct.pack('<H', len(p)) + p)


def load(path):
    data, out, i = open(path, 'rb').read(), [], 0
    while i + 2 <= len(data):
        (n,) = struct.unpack_from('<H', data, i)
        out.append(data[i + 2:i + 2 + n])
        i += 2 + n
    return out


def _with(p, offset, value):
    return p[:offset] + value + p[offset + len(value):]


def _other_key_state(rng, p):
    """A well-formed state packet (fresh seq) signed with a key that is not the deployment's."""
    body = _with(p[:-TAG], SEQ_OFFSET, struct.pack('<I', rng.getrandbits(32)))
    return tp.Mac(bytes(rng.getrandbits(8) for _ in range(32))).sign(body)


MALFORMED = (
    ('random', lambda rng, p: bytes(rng.getrandbits(8) for _ in range(rng.randint(6, 300)))),
    ('short', lambda rng, p: p[:rng.randint(0, 5)]),
    ('magic', lambda rng, p: _with(p, 0, b'XBAL')),
    ('version_1', lambda rng, p: _with(p, 4, b'\x01')),
    ('version_3', lambda rng, p: _with(p, 4, b'\x03')),
    ('type', lambda rng, p: _with(p, 5, b'\x02')),
    ('size', lambda rng, p: p[:rng.randint(6, STATE_SIZE - 1)]),
    ('bad_tag', lambda rng, p: p[:-TAG] + bytes(rng.getrandbits(8) for _ in range(TAG))),
    ('changed_field', lambda rng, p: _with(p, SEQ_OFFSET, struct.pack(
        '<I', (struct.unpack_from('<I', p, SEQ_OFFSET)[0] + 1000) & 0xFFFFFFFF))),
    ('other_key', _other_key_state),
)


def malformed_stream(captured, rng):
    """Endless (kind, datagram): every malformed kind in turn, built on captured packets."""
    while True:
        for kind, make in MALFORMED:
            yield kind, make(rng, rng.choice(captured))


def replay_stream(captured):
    while True:
        for p in captured:
            yield 'replayed', p


def flood_stream(captured, rng):
    m, r = malformed_stream(captured, rng), replay_stream(captured)
    while True:
        yield next(r)
        yield next(m)


def send(stream, port, seconds, rate, clock=time.time, sleep=time.sleep):
    """Send ``rate`` datagrams/s from ``stream`` to 127.0.0.1:``port`` for ``seconds``, paced in
    2 ms ticks. Returns (t_start, t_end, {kind: count})."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    counts, sent = {}, 0
    start = clock()
    try:
        while True:
            now = clock()
            if now - start >= seconds:
                break
            due = int((now - start) * rate) + 1
            while sent < due:
                kind, data = next(stream)
                try:
                    s.sendto(data, ('127.0.0.1', port))
                except OSError:             # a full send buffer: counted as not sent
                    kind += '_unsent'
                counts[kind] = counts.get(kind, 0) + 1
                sent += 1
            sleep(0.002)
    finally:
        s.close()
    return start, clock(), counts


def main(argv):
    if len(argv) < 5:
        sys.stderr.write(__doc__)
        return 2
    cmd, port, seconds = argv[1], int(argv[2]), float(argv[3])
    if cmd == 'capture':
        got = capture(port, seconds)
        save(got, argv[4])
        print(len(got))
        return 0 if got else 1
    rate, captured = float(argv[4]), load(argv[5])
    if not captured:
        sys.stderr.write('packets.py: no captured packets in %s\n' % argv[5])
        return 1
    rng = random.Random(int(os.environ.get('FAULTS_SEED', '7')))
    stream = {'malformed': lambda: malformed_stream(captured, rng), 'replay': lambda: replay_stream(captured),
              'flood': lambda: flood_stream(captured, rng)}.get(cmd)
    if stream is None:
        sys.stderr.write(__doc__)
        return 2
    t0, t1, counts = send(stream(), port, seconds, rate)
    print('%.6f %.6f %d' % (t0, t1, sum(v for k, v in counts.items() if not k.endswith('_unsent'))))
    sys.stderr.write(' '.join('%s=%d' % kv for kv in sorted(counts.items())) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
