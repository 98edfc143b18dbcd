"""Touchball protocol v2 (saras_drivers.touchball_protocol, touchball_session, keys): layout, tags,
test vectors (shared with the C++ gtest and docs/touchball_protocol.md), rejection reasons,
sequence tracking, console-side handshake, key files."""
import hashlib
import hmac
import math
import os
import random
import struct

import pytest

from saras_drivers import keys
from saras_drivers import touchball_protocol as tp
from saras_drivers.touchball_session import ConsoleSession

HERE = os.path.dirname(os.path.abspath(__file__))
VECTORS = os.path.join(HERE, 'touchball', 'data', 'test_vectors.txt')
DOC = os.path.join(HERE, '..', 'docs', 'touchball_protocol.md')
KEY = bytes(range(32))
MAC = tp.Mac(KEY)
S = 0x0123456789ABCDEF


def _devices():
    return (tp.DeviceState((0.01, -0.02, 0.03), (0.0, 0.0, math.sin(0.25), math.cos(0.25)), 0.4, True, False),
            tp.DeviceState((-0.1, 0.2, 0.05), (1.0, 0.0, 0.0, 0.0), 0.0, False, True))


def _vectors():
    out = {}
    with open(VECTORS) as f:
        for line in f:
            if line.strip() and not line.startswith('#'):
                name, key, packet, full = line.split()
                out[name] = (bytes.fromhex(key), bytes.fromhex(packet), bytes.fromhex(full))
    return out


def test_vectors_match_encoder_hmac_and_document():
    v = _vectors()
    assert sorted(v) == ['challenge', 'command', 'hello', 'state']
    left = tp.DeviceState((-0.12, 0.01, 0.07), (0, 0, math.sin(0.25), math.cos(0.25)), 0.3, True, False)
    right = tp.DeviceState((0.1, -0.02, 0.05), (0.5, 0.5, 0.5, 0.5), 0.75, False, True)
    built = {'state': tp.pack_state(MAC, S, 0xFFFFFFFE, 1700000000.25, (left, right)),
             'command': tp.pack_command(MAC, S, 7, 12.5, (tp.DeviceCommand((1, -2, 0.5), (0, 0, 0), True),
                                                          tp.ZERO_COMMAND)),
             'hello': tp.pack_hello(MAC, 0x1122334455667788, 3, 1700000000.0),
             'challenge': tp.pack_challenge(MAC, S, 0x1122334455667788, 1, 1700000000.125)}
    doc = open(DOC).read().replace('\n', '').replace(' ', '')
    for name, (key, packet, full) in v.items():
        assert key == KEY
        assert built[name] == packet, name
        assert hmac.new(key, packet[:-16], hashlib.sha256).digest() == full
        assert packet[-16:] == full[:16]
        assert packet.hex() in doc and full.hex() in doc, 'docs/touchball_protocol.md lacks the %s vector' % name


def test_sizes_and_layout():
    assert (tp.STATE_SIZE, tp.COMMAND_SIZE, tp.HELLO_SIZE, tp.CHALLENGE_SIZE) == (180, 148, 44, 52)
    data = tp.pack_state(MAC, S, 0x01020304, 2.25, _devices())
    assert data[0:4] == b'TBAL' and data[4] == 2 and data[5] == 1
    assert data[8:12] == bytes([4, 3, 2, 1])              # little-endian seq
    assert struct.unpack('<d', data[12:20])[0] == 2.25
    assert struct.unpack('<Q', data[20:28])[0] == S
    assert struct.unpack('<d', data[28:36])[0] == 0.01    # left x at 28
    assert struct.unpack('<I', data[28 + 68 + 64:28 + 68 + 68])[0] == tp.BUTTON_CLIP
    assert data[164:] == MAC.tag(data[:164])
    cmds = (tp.DeviceCommand((1.0, -2.0, 0.5), (0.25, 0.0, 0.1), True),
            tp.DeviceCommand((0.0, 3.0, 0.0), (0.0, 0.0, 0.0), False))
    c = tp.pack_command(MAC, S, 0x0A0B0C0D, 7.5, cmds)
    assert struct.unpack_from('<IdQ', c, 8) == (0x0A0B0C0D, 7.5, S)
    assert struct.unpack_from('<6dI', c, 28) == (1.0, -2.0, 0.5, 0.25, 0.0, 0.1, 1)
    assert struct.unpack_from('<6dI', c, 80) == (0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0)
    assert tp.unpack_command(c, MAC, S).devices == cmds


def test_state_round_trip():
    pkt = tp.unpack_state(tp.pack_state(MAC, S, 42, 3.5, _devices()), MAC, S)
    assert (pkt.seq, pkt.sender_time, pkt.session) == (42, 3.5, S)
    for got, want in zip(pkt.devices, _devices()):
        assert got.position == pytest.approx(want.position, abs=0)
        assert got.orientation == pytest.approx(want.orientation, abs=1e-15)
        assert (got.clip_angle, got.clutch, got.clip_button) == (want.clip_angle, want.clutch, want.clip_button)


def _v1(data):
    """The same state as a version-1 packet (160 bytes, CRC-32): what an attacker can forge."""
    import zlib
    body = data[:4] + b'\x01' + data[5:20] + data[28:164]
    return body + struct.pack('<I', zlib.crc32(body))


@pytest.mark.parametrize('mutate,reason', [
    (lambda b: b[:-1], 'size'),
    (lambda b: b + b'\0', 'size'),
    (lambda b: b[:3], 'size'),
    (lambda b: b'XBAL' + b[4:], 'magic'),
    (_v1, 'version'),
    (lambda b: b[:5] + b'\x07' + b[6:], 'type'),
    (lambda b: b[:100] + bytes([b[100] ^ 1]) + b[101:], 'mac'),
    (lambda b: tp.Mac(bytes(32)).sign(b[:-16]), 'mac'),                       # another key
    (lambda b: MAC.sign(b[:20] + struct.pack('<Q', S + 1) + b[28:-16]), 'session'),
    (lambda b: MAC.sign(b[:28] + struct.pack('<d', float('nan')) + b[36:-16]), 'non_finite'),
    (lambda b: MAC.sign(b[:52] + struct.pack('<4d', 0.0, 0.0, 0.0, 0.5) + b[84:-16]), 'quaternion'),
])
def test_rejections(mutate, reason):
    data = tp.pack_state(MAC, S, 1, 0.0, _devices())
    with pytest.raises(tp.ProtocolError) as e:
        tp.unpack_state(mutate(data), MAC, S)
    assert e.value.reason == reason


def test_bit_flips_never_accepted():
    data = tp.pack_state(MAC, S, 1, 0.0, _devices())
    for k in range(len(data) * 8):
        b = bytearray(data)
        b[k // 8] ^= 1 << (k % 8)
        with pytest.raises(tp.ProtocolError):
            tp.unpack_state(bytes(b), MAC, S)


def test_sequence_tracker_gaps_duplicates_reorder_and_wrap():
    s = tp.SequenceTracker()
    assert s.accept(10) == 0
    assert s.accept(15) == 4 and s.gaps == 4
    for bad, reason in ((15, 'duplicate'), (14, 'out_of_order'), (11, 'out_of_order')):
        with pytest.raises(tp.ProtocolError) as e:
            s.accept(bad)
        assert e.value.reason == reason
    s.reset()
    assert s.accept(0xFFFFFFFF) == 0
    assert s.accept(1) == 1                               # wrapped, 0 missing


def test_decode_huge_finite_values_are_not_mistaken_for_non_finite():
    d = tp.DeviceState((1e308, 1e308, 1e308), (0.0, 0.0, 0.0, 1.0), 1e308, False, False)
    _seq, _t, _s, left, _right = tp.decode_state(tp.pack_state(MAC, S, 3, 1.0, (d, d)), MAC, S)
    assert left[:3] == (1e308, 1e308, 1e308)
    with pytest.raises(tp.ProtocolError) as e:
        tp.decode_state(tp.pack_state(MAC, S, 3, float('inf'), (d, d)), MAC, S)
    assert e.value.reason == 'non_finite' and 'sender_time' in str(e.value)


def test_console_session_handshake_commands_and_rebind():
    nonces = iter([11, 22, 33])
    c = ConsoleSession(MAC, hello_interval=0.1, rebind_after=1.0, nonce_source=lambda: next(nonces))
    hello = c.outgoing(_devices(), 100.0, 0.0)
    assert tp.unpack_hello(hello, MAC)[2] == 11
    assert c.outgoing(_devices(), 100.0, 0.05) is None                 # next hello after 0.1 s
    assert c.handle(tp.pack_challenge(MAC, S, 99, 0, 1.0), 0.06) is None   # not our nonce
    assert c.handle(tp.pack_challenge(tp.Mac(bytes(32)), S, 11, 0, 1.0), 0.06) is None   # other key
    assert c.handle(tp.pack_challenge(MAC, S, 11, 0, 1.0), 0.07) == 'challenge'
    state = c.outgoing(_devices(), 100.1, 0.08)
    assert tp.unpack_state(state, MAC, S).session == S
    cmd = tp.pack_command(MAC, S, 5, 1.0, (tp.DeviceCommand((1, 0, 0), (0, 0, 0), True), tp.ZERO_COMMAND))
    assert c.handle(cmd, 0.09) == 'command' and c.commands[0].enabled
    assert c.handle(cmd, 0.10) is None                                 # replayed command
    assert c.handle(tp.pack_command(MAC, S + 1, 6, 1.0, c.commands), 0.11) is None    # other session
    assert c.rejected == {'session': 2, 'mac': 1, 'duplicate': 1}
    assert c.outgoing(_devices(), 101.0, 1.05)[5] == tp.TYPE_STATE and c.bound   # 0.96 s since the command
    assert tp.unpack_hello(c.outgoing(_devices(), 101.0, 1.2), MAC)[2] == 22    # 1.11 s: rebind, new nonce
    assert not c.bound


def test_key_files(tmp_path):
    p = str(tmp_path / 'console.key')
    key = keys.write_key_file(p)
    assert os.stat(p).st_mode & 0o777 == 0o600 and len(key) == 32
    assert keys.read_key_file(p) == key
    with pytest.raises(OSError):
        keys.write_key_file(p)                                         # never overwrites
    os.chmod(p, 0o640)
    with pytest.raises(keys.KeyFileError) as e:
        keys.read_key_file(p)
    assert p in str(e.value) and '0640' in str(e.value)
    with pytest.raises(keys.KeyFileError) as e:
        keys.read_key_file(p + '.missing')
    assert p + '.missing' in str(e.value)
    with pytest.raises(keys.KeyFileError):
        keys.read_key_file('')
    for text in ('ab' * 31, 'ab' * 65, 'zz' * 32, 'ab' * 32 + '\n' + 'ab' * 32):
        with pytest.raises(ValueError):
            keys.parse_key_text(text)
    assert keys.parse_key_text('# comment\n  ' + 'AB' * 32 + ' \r\n') == b'\xab' * 32
    rng = random.Random(1)
    assert keys.parse_key_text(bytes(rng.getrandbits(8) for _ in range(64)).hex())
