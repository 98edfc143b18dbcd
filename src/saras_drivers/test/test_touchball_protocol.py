"""Touchball wire format: round trip, byte layout against an independent hand-made encoding,
CRC against the standard CRC-32 check value, sequence arithmetic."""
import binascii
import math
import struct

import pytest

from saras_drivers import touchball_protocol as tp


def _devices():
    return (tp.DeviceState((0.01, -0.02, 0.03), (0.0, 0.0, math.sin(0.25), math.cos(0.25)), 0.4, True, False),
            tp.DeviceState((-0.1, 0.2, 0.05), (1.0, 0.0, 0.0, 0.0), 0.0, False, True))


def test_crc_is_standard_crc32():
    # Standard CRC-32 (IEEE 802.3) check value of "123456789".
    assert binascii.crc32(b'123456789') == 0xCBF43926
    data = tp.pack_state(7, 1.5, _devices())
    assert struct.unpack('<I', data[-4:])[0] == binascii.crc32(data[:-4])


def test_state_sizes_and_layout():
    assert tp.STATE_SIZE == 160 and tp.COMMAND_SIZE == 128
    data = tp.pack_state(0x01020304, 2.25, _devices())
    assert len(data) == 160
    assert data[0:4] == b'TBAL' and data[4] == 1 and data[5] == 1
    assert data[8:12] == bytes([4, 3, 2, 1])              # little-endian seq
    assert struct.unpack('<d', data[12:20])[0] == 2.25
    # left device x at offset 20, right device buttons at 20 + 68 + 64
    assert struct.unpack('<d', data[20:28])[0] == 0.01
    assert struct.unpack('<I', data[20 + 68 + 64:20 + 68 + 68])[0] == tp.BUTTON_CLIP
    assert struct.unpack('<I', data[20 + 64:20 + 68])[0] == tp.BUTTON_CLUTCH


def test_state_round_trip():
    pkt = tp.unpack_state(tp.pack_state(42, 3.5, _devices()))
    assert pkt.seq == 42 and pkt.sender_time == 3.5
    for got, want in zip(pkt.devices, _devices()):
        assert got.position == pytest.approx(want.position, abs=0)
        assert got.orientation == pytest.approx(want.orientation, abs=1e-15)
        assert (got.clip_angle, got.clutch, got.clip_button) == (want.clip_angle, want.clutch, want.clip_button)


def test_command_round_trip():
    cmds = (tp.DeviceCommand((1.0, -2.0, 0.5), (0.0, 0.0, 0.1), True), tp.ZERO_COMMAND)
    data = tp.pack_command(9, 0.125, cmds)
    assert len(data) == tp.COMMAND_SIZE and data[5] == tp.TYPE_COMMAND
    pkt = tp.unpack_command(data)
    assert pkt.seq == 9 and pkt.devices[0] == cmds[0] and pkt.devices[1] == cmds[1]


@pytest.mark.parametrize('mutate,reason', [
    (lambda b: b[:-1], 'size'),
    (lambda b: b + b'\0', 'size'),
    (lambda b: b'XBAL' + b[4:], 'magic'),
    (lambda b: b[:4] + b'\x02' + b[5:], 'version'),
    (lambda b: b[:100] + bytes([b[100] ^ 1]) + b[101:], 'crc'),
])
def test_rejections(mutate, reason):
    data = tp.pack_state(1, 0.0, _devices())
    with pytest.raises(tp.ProtocolError) as e:
        tp.unpack_state(mutate(data))
    assert e.value.reason == reason


def _reframe(body):
    return body + struct.pack('<I', binascii.crc32(body))


def test_type_nan_and_quaternion_rejected_even_with_valid_crc():
    data = tp.pack_state(1, 0.0, _devices())
    with pytest.raises(tp.ProtocolError) as e:
        tp.unpack_command(data[:128])                     # right size, state type
    assert e.value.reason == 'type'
    typed = _reframe(data[:5] + b'\x02' + data[6:-4])
    with pytest.raises(tp.ProtocolError) as e:
        tp.unpack_state(typed)
    assert e.value.reason == 'type'
    nan = _reframe(data[:20] + struct.pack('<d', float('nan')) + data[28:-4])
    with pytest.raises(tp.ProtocolError) as e:
        tp.unpack_state(nan)
    assert e.value.reason == 'non_finite'
    badq = _reframe(data[:20 + 24] + struct.pack('<4d', 0.0, 0.0, 0.0, 0.5) + data[20 + 56:-4])
    with pytest.raises(tp.ProtocolError) as e:
        tp.unpack_state(badq)
    assert e.value.reason == 'quaternion'


def test_sequence_tracker_gaps_duplicates_reorder_and_wrap():
    s = tp.SequenceTracker()
    assert s.accept(10) == 0
    assert s.accept(11) == 0
    assert s.accept(15) == 3 and s.gaps == 3
    for bad, reason in ((15, 'duplicate'), (14, 'out_of_order'), (11, 'out_of_order')):
        with pytest.raises(tp.ProtocolError) as e:
            s.accept(bad)
        assert e.value.reason == reason
    s.reset()
    assert s.accept(0xFFFFFFFE) == 0
    assert s.accept(0xFFFFFFFF) == 0
    assert s.accept(1) == 1                               # wrapped, 0 missing
    assert s.gaps == 4


def _reference_decode(data):
    """Independent field-by-field decode (hand offsets), for the single-struct fast path."""
    seq, t = struct.unpack_from('<Id', data, 8)
    devs = []
    for off in (20, 88):
        v = struct.unpack_from('<8dI', data, off)
        n = math.sqrt(sum(x * x for x in v[3:7]))
        devs.append(v[0:3] + tuple(x / n for x in v[3:7]) + v[7:9])
    return seq, t, devs[0], devs[1]


def test_decode_state_fast_path_matches_field_by_field_decode():
    import random
    rng = random.Random(7)
    for k in range(300):
        devs = []
        for _ in range(2):
            q = [rng.gauss(0, 1) for _ in range(4)]
            n = math.sqrt(sum(x * x for x in q))
            devs.append(tp.DeviceState(tuple(rng.uniform(-1, 1) for _ in range(3)),
                                       tuple(x / n * (1 + rng.uniform(-5e-4, 5e-4)) for x in q),
                                       rng.uniform(0, 1), rng.random() < 0.5, rng.random() < 0.5))
        data = tp.pack_state(rng.getrandbits(32), rng.uniform(0, 1e9), devs)
        seq, t, left, right = tp.decode_state(data)
        rseq, rt, rleft, rright = _reference_decode(data)
        assert (seq, t) == (rseq, rt)
        assert left == pytest.approx(rleft, rel=0, abs=1e-15)
        assert right == pytest.approx(rright, rel=0, abs=1e-15)
        assert left[8] == (1 if devs[0].clutch else 0) | (2 if devs[0].clip_button else 0)


def test_decode_state_huge_finite_values_are_not_mistaken_for_non_finite():
    # the fast finiteness test sums the fields; 1e308 + 1e308 overflows to inf, the exact
    # fallback must still accept the (absurd but finite) packet
    d = tp.DeviceState((1e308, 1e308, 1e308), (0.0, 0.0, 0.0, 1.0), 1e308, False, False)
    seq, t, left, right = tp.decode_state(tp.pack_state(3, 1.0, (d, d)))
    assert left[:3] == (1e308, 1e308, 1e308)
    nan = tp.DeviceState((0.0, float('nan'), 0.0), (0.0, 0.0, 0.0, 1.0), 0.0, False, False)
    with pytest.raises(tp.ProtocolError) as e:
        tp.decode_state(tp.pack_state(3, 1.0, (d, nan)))
    assert e.value.reason == 'non_finite'
    inf_t = tp.pack_state(3, float('inf'), (d, d))
    with pytest.raises(tp.ProtocolError) as e:
        tp.decode_state(inf_t)
    assert e.value.reason == 'non_finite' and 'sender_time' in str(e.value)


def test_command_layout_against_hand_offsets():
    cmds = (tp.DeviceCommand((1.0, -2.0, 0.5), (0.25, 0.0, 0.1), True),
            tp.DeviceCommand((0.0, 3.0, 0.0), (0.0, 0.0, 0.0), False))
    data = tp.pack_command(0x0A0B0C0D, 7.5, cmds)
    assert data[0:4] == b'TBAL' and data[4] == 1 and data[5] == 2
    assert struct.unpack_from('<Id', data, 8) == (0x0A0B0C0D, 7.5)
    assert struct.unpack_from('<6dI', data, 20) == (1.0, -2.0, 0.5, 0.25, 0.0, 0.1, 1)
    assert struct.unpack_from('<6dI', data, 72) == (0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0)
    assert struct.unpack_from('<I', data, 124)[0] == binascii.crc32(data[:124])
