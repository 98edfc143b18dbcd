"""The fault suite's hostile console datagrams (scripts/faults/packets.py): every malformed kind and
every replayed packet is refused by the receiver's validation rules (saras_drivers'
touchball_protocol, the Python twin of the C++ receiver checked against the same test vectors),
the capture parser finds the UDP payload of a loopback frame, and the sender keeps its rate."""
import os
import random
import struct
import sys

import pytest

WS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(WS, 'scripts', 'faults'))
import packets  # noqa: E402

tp = pytest.importorskip('saras_drivers.touchball_protocol')

KEY = bytes(range(32))
SESSION = 0x0123456789ABCDEF
DEV = tp.DeviceState((0.1, 0.0, 0.05), (0.0, 0.0, 0.0, 1.0), 0.3, False, False)


def stream(n=20):
    mac = tp.Mac(KEY)
    return [tp.pack_state(mac, SESSION, seq, 1.0 + seq, (DEV, DEV)) for seq in range(100, 100 + n)]


def receiver():
    """accept(datagram) -> None or the rejection reason, with the receiver's session and sequence rules."""
    mac, seqs = tp.Mac(KEY), tp.SequenceTracker()

    def accept(data):
        try:
            seq = tp.decode_state(data, mac, SESSION)[0]
            seqs.accept(seq)
        except tp.ProtocolError as e:
            return e.reason
        return None
    return accept


def test_every_malformed_kind_is_refused_for_its_reason():
    captured, rng, accept = stream(), random.Random(3), receiver()
    expected = {'short': {'size'}, 'magic': {'magic'}, 'version_1': {'version'}, 'version_3': {'version'},
                'type': {'type'}, 'size': {'size'}, 'bad_tag': {'mac'}, 'changed_field': {'mac'},
                'other_key': {'mac'}, 'random': {'magic', 'size'}}
    seen = set()
    gen = packets.malformed_stream(captured, rng)
    for _ in range(10 * len(packets.MALFORMED)):
        kind, data = next(gen)
        seen.add(kind)
        assert accept(data) in expected[kind], kind
    assert seen == set(expected)
    assert accept(captured[0]) is None           # the receiver still takes the real stream


def test_replayed_packets_are_refused_after_the_real_ones():
    captured, accept = stream(), receiver()
    assert [accept(p) for p in captured] == [None] * len(captured)
    gen = packets.replay_stream(captured)
    reasons = [accept(next(gen)[1]) for _ in range(2 * len(captured))]
    assert set(reasons) <= {'duplicate', 'out_of_order'} and None not in reasons


def test_flood_interleaves_replayed_and_malformed():
    gen = packets.flood_stream(stream(), random.Random(1))
    kinds = [next(gen)[0] for _ in range(40)]
    assert kinds[::2] == ['replayed'] * 20 and 'replayed' not in kinds[1::2]


def test_capture_parser_takes_the_udp_payload_to_the_port_only():
    payload = stream(1)[0]
    udp = struct.pack('!HHHH', 40000, 8888, 8 + len(payload), 0) + payload
    ip = bytes([0x45, 0]) + struct.pack('!H', 20 + len(udp)) + bytes(5) + bytes([17]) + bytes(10)
    frame = bytes(12) + b'\x08\x00' + ip + udp
    assert packets.udp_payload(frame, 8888) == payload
    assert packets.udp_payload(frame, 8889) is None
    assert packets.udp_payload(frame[:30], 8888) is None


def test_send_paces_the_rate_and_counts_each_kind():
    t = [0.0]
    gen = packets.malformed_stream(stream(), random.Random(2))
    start, end, counts = packets.send(gen, 9, 0.5, 1000.0, clock=lambda: t[0],
                                      sleep=lambda dt: t.__setitem__(0, t[0] + dt))
    total = sum(counts.values())
    assert (start, end) == (0.0, pytest.approx(0.5, abs=0.003))
    assert 495 <= total <= 505
    assert set(k.replace('_unsent', '') for k in counts) == set(k for k, _ in packets.MALFORMED)


def test_save_and_load_round_trip(tmp_path):
    captured = stream(3) + [b'', b'x']
    packets.save(captured, str(tmp_path / 'c.bin'))
    assert packets.load(str(tmp_path / 'c.bin')) == captured
