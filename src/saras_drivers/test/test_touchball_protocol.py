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
