"""Touchball console link: the versioned UDP packet formats (protocol version 2, authenticated).

This module is the ONE Python implementation of the wire format (the C++ receiver has its own in
touchball_protocol.cpp; both are checked against the test vectors of the document). The console
simulator, the tests and the benchmarks use it. It has no ROS dependency.

All fields are little-endian. See ``docs/touchball_protocol.md`` for the normative description.

Header, 28 bytes::

    magic 'TBAL' (4s) | version u8 = 2 | type u8 | flags u16 = 0 | seq u32 | sender_time f64 [s] | session u64

Every packet ends with a 16-byte tag = the first 16 bytes of HMAC-SHA256(key, all preceding bytes).

STATE (1, console -> ROS, 180 bytes): header (session = the session nonce), two devices (left, right),
68 bytes each: position 3 x f64 [m] in touch_<side>/base, orientation quaternion 4 x f64 (x, y, z, w),
clip_angle f64 [rad], buttons u32 (bit 0 clutch, bit 1 clip button); tag.
COMMAND (2, ROS -> console, 148 bytes): header (session nonce), two devices, 52 bytes each: force
3 x f64 [N], torque 3 x f64 [N m] in touch_<side>/base, flags u32 (bit 0 ENABLED); tag.
HELLO (3, console -> ROS, 44 bytes): header (session = the console's random nonce); tag.
CHALLENGE (4, ROS -> console, 52 bytes): header (session = the new session nonce), the hello's
console nonce u64; tag.
"""

import math
import hashlib
import hmac
import struct
from collections import namedtuple

MAGIC = b'TBAL'
VERSION = 2
TYPE_STATE = 1
TYPE_COMMAND = 2
TYPE_HELLO = 3
TYPE_CHALLENGE = 4

DEVICES = ('left', 'right')

BUTTON_CLUTCH = 0x1
BUTTON_CLIP = 0x2
CMD_ENABLED = 0x1

TAG_SIZE = 16               # [bytes] HMAC-SHA256 truncated to 128 bits
HEADER = struct.Struct('<4sBBHIdQ')
STATE_DEVICE = struct.Struct('<3d4ddI')
COMMAND_DEVICE = struct.Struct('<3d3dI')
NONCE = struct.Struct('<Q')

STATE_SIZE = HEADER.size + 2 * STATE_DEVICE.size + TAG_SIZE
COMMAND_SIZE = HEADER.size + 2 * COMMAND_DEVICE.size + TAG_SIZE
HELLO_SIZE = HEADER.size + TAG_SIZE
CHALLENGE_SIZE = HEADER.size + NONCE.size + TAG_SIZE
SIZES = {TYPE_STATE: STATE_SIZE, TYPE_COMMAND: COMMAND_SIZE, TYPE_HELLO: HELLO_SIZE,
         TYPE_CHALLENGE: CHALLENGE_SIZE}

# Whole-packet layouts (everything before the tag) for the single-call hot paths.
_STATE_BODY = struct.Struct('<4sBBHIdQ3d4ddI3d4ddI')
_COMMAND_BODY = struct.Struct('<4sBBHIdQ3d3dI3d3dI')
_CHALLENGE_BODY = struct.Struct('<4sBBHIdQQ')
assert _STATE_BODY.size + TAG_SIZE == STATE_SIZE and _COMMAND_BODY.size + TAG_SIZE == COMMAND_SIZE
assert (STATE_SIZE, COMMAND_SIZE, HELLO_SIZE, CHALLENGE_SIZE) == (180, 148, 44, 52)

#: Accepted deviation of the quaternion norm from 1 before a packet is rejected.
QUATERNION_NORM_TOLERANCE = 1e-3

#: Reasons a datagram can be rejected; every rejection is counted under exactly one of them.
REJECT_REASONS = ('foreign_source', 'size', 'magic', 'version', 'type', 'mac', 'session',
                  'non_finite', 'quaternion', 'duplicate', 'out_of_order')

DeviceState = namedtuple('DeviceState', 'position orientation clip_angle clutch clip_button')
DeviceState.__doc__ = """One device in a state packet.

position: (x, y, z) [m]; orientation: (x, y, z, w) unit quaternion; clip_angle [rad];
clutch, clip_button: bool."""

StatePacket = namedtuple('StatePacket', 'seq sender_time session devices')
StatePacket.__doc__ = "Decoded state packet: seq (u32), sender_time [s], session (u64), devices (left, right)."

DeviceCommand = namedtuple('DeviceCommand', 'force torque enabled')
DeviceCommand.__doc__ = "force (3) [N], torque (3) [N m] in touch_<side>/base, enabled (bool)."

CommandPacket = namedtuple('CommandPacket', 'seq sender_time session devices')
Challenge = namedtuple('Challenge', 'seq sender_time session console_nonce')

ZERO_COMMAND = DeviceCommand((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), False)


class ProtocolError(ValueError):
    """A datagram that is not a valid packet; ``reason`` is one of :data:`REJECT_REASONS`."""

    def __init__(self, reason, detail=''):
        super(ProtocolError, self).__init__('%s: %s' % (reason, detail) if detail else reason)
        self.reason = reason


class Mac(object):
    """HMAC-SHA256 with one key, truncated to :data:`TAG_SIZE` bytes (the key hashed once)."""

    def __init__(self, key):
        key = bytes(key)
        if not 32 <= len(key) <= 64:
            raise ValueError('the key must be 32 to 64 bytes, got %d' % len(key))
        self._h = hmac.new(key, digestmod=hashlib.sha256)

    def full(self, data):
        h = self._h.copy()
        h.update(data)
        return h.digest()

    def tag(self, data):
        return self.full(data)[:TAG_SIZE]

    def sign(self, body):
        """``body`` followed by its tag."""
        return body + self.tag(body)

    def verify(self, data):
        """True if the last TAG_SIZE bytes of ``data`` are the tag of the bytes before them."""
        n = len(data) - TAG_SIZE
        return n > 0 and hmac.compare_digest(self.tag(memoryview(data)[:n]), bytes(data[n:]))


def _buttons(clutch, clip):
    return (BUTTON_CLUTCH if clutch else 0) | (BUTTON_CLIP if clip else 0)


def pack_state(mac, session, seq, sender_time, devices):
    """Encode a state packet bound to ``session``. ``devices`` = (left, right) :class:`DeviceState`."""
    if len(devices) != 2:
        raise ValueError('a state packet carries exactly two devices')
    (lp, lq, lc, lcl, lcb), (rp, rq, rc, rcl, rcb) = devices
    return mac.sign(_STATE_BODY.pack(MAGIC, VERSION, TYPE_STATE, 0, seq & 0xFFFFFFFF, float(sender_time), session,
                                     lp[0], lp[1], lp[2], lq[0], lq[1], lq[2], lq[3], lc, _buttons(lcl, lcb),
                                     rp[0], rp[1], rp[2], rq[0], rq[1], rq[2], rq[3], rc, _buttons(rcl, rcb)))


def pack_command(mac, session, seq, sender_time, commands):
    """Encode a command packet. ``commands`` = (left, right) :class:`DeviceCommand`."""
    if len(commands) != 2:
        raise ValueError('a command packet carries exactly two devices')
    (lf, lt, le), (rf, rt, re) = commands
    return mac.sign(_COMMAND_BODY.pack(MAGIC, VERSION, TYPE_COMMAND, 0, seq & 0xFFFFFFFF, float(sender_time),
                                       session, lf[0], lf[1], lf[2], lt[0], lt[1], lt[2], CMD_ENABLED if le else 0,
                                       rf[0], rf[1], rf[2], rt[0], rt[1], rt[2], CMD_ENABLED if re else 0))


def pack_hello(mac, console_nonce, seq, sender_time):
    """Encode a hello (console -> ROS): asks for a session, carrying the console's nonce."""
    return mac.sign(HEADER.pack(MAGIC, VERSION, TYPE_HELLO, 0, seq & 0xFFFFFFFF, float(sender_time), console_nonce))


def pack_challenge(mac, session, console_nonce, seq, sender_time):
    """Encode a challenge (ROS -> console): the new ``session`` for the hello of ``console_nonce``."""
    return mac.sign(_CHALLENGE_BODY.pack(MAGIC, VERSION, TYPE_CHALLENGE, 0, seq & 0xFFFFFFFF, float(sender_time),
                                         session, console_nonce))


def check_frame(data, mac, types):
    """Validate size, magic, version, type (one of ``types``), exact size and tag, in this order.

    Returns ``(type, seq, sender_time, session)``; raises :class:`ProtocolError`. A version-1
    packet is refused (``version``) without being parsed further.
    """
    if len(data) < 6:
        raise ProtocolError('size', 'got %d bytes' % len(data))
    if bytes(data[:4]) != MAGIC:
        raise ProtocolError('magic', repr(bytes(data[:4])))
    if data[4] != VERSION:
        raise ProtocolError('version', 'got %d, expected %d (version 1 is unauthenticated and refused)'
                            % (data[4], VERSION))
    if data[5] not in types:
        raise ProtocolError('type', 'got %d' % data[5])
    if len(data) != SIZES[data[5]]:
        raise ProtocolError('size', 'got %d bytes, expected %d' % (len(data), SIZES[data[5]]))
    if not mac.verify(data):
        raise ProtocolError('mac')
    _m, _v, t, _f, seq, sender_time, session = HEADER.unpack_from(data, 0)
    return t, seq, sender_time, session


def _check_session(got, expected):
    if expected is not None and (expected == 0 or got != expected):
        raise ProtocolError('session', 'packet of session %016x, current %016x' % (got, expected or 0))


def decode_state(data, mac, session=None):
    """Decode and validate a state packet with one ``struct`` call.

    Returns ``(seq, sender_time, session, left, right)`` where each device is the flat tuple
    ``(x, y, z, qx, qy, qz, qw, clip_angle, buttons)`` [m, unit quaternion, rad, bit mask] with the
    quaternion re-normalised. Raises :class:`ProtocolError`; checks in this order, the first
    failing one is the reason: size, magic, version, type, size, mac, session (unless ``session``
    is None), non_finite (any field, sender time first), quaternion (left, then right).
    """
    check_frame(data, mac, (TYPE_STATE,))
    v = _STATE_BODY.unpack_from(data)
    # v: magic, version, type, flags, seq, sender_time, session, left (8 floats, buttons), right (...)
    _check_session(v[6], session)
    if not math.isfinite(v[5] + sum(v[7:15]) + sum(v[16:24])):
        _check_finite(v)                                # raises (or a finite overflow: passes)
    out = [v[4], v[5], v[6]]
    for o in (7, 16):
        qx, qy, qz, qw = v[o + 3], v[o + 4], v[o + 5], v[o + 6]
        n = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if abs(n - 1.0) > QUATERNION_NORM_TOLERANCE:
            raise ProtocolError('quaternion', 'norm %g' % n)
        out.append((v[o], v[o + 1], v[o + 2], qx / n, qy / n, qz / n, qw / n, v[o + 7], v[o + 8]))
    return tuple(out)


def _check_finite(v):
    """Field-by-field finiteness check of an unpacked state body, in wire order."""
    if not math.isfinite(v[5]):
        raise ProtocolError('non_finite', 'sender_time')
    for o in (7, 16):
        if not all(math.isfinite(x) for x in v[o:o + 8]):
            raise ProtocolError('non_finite', 'device field')


def device_state(flat):
    """:class:`DeviceState` of one flat device tuple returned by :func:`decode_state`."""
    return DeviceState(flat[0:3], flat[3:7], flat[7], bool(flat[8] & BUTTON_CLUTCH),
                       bool(flat[8] & BUTTON_CLIP))


def unpack_state(data, mac, session=None):
    """Decode and validate a state packet; raises :class:`ProtocolError` on any defect.

    The quaternion must have a norm within :data:`QUATERNION_NORM_TOLERANCE` of 1; it is
    returned re-normalised.
    """
    seq, sender_time, sess, left, right = decode_state(data, mac, session)
    return StatePacket(seq, sender_time, sess, (device_state(left), device_state(right)))


def unpack_command(data, mac, session=None):
    """Decode and validate a command packet; raises :class:`ProtocolError` on any defect."""
    check_frame(data, mac, (TYPE_COMMAND,))
    v = _COMMAND_BODY.unpack_from(data)
    # v: header (7), left force (3), torque (3), flags, right force, torque, flags
    _check_session(v[6], session)
    if not math.isfinite(v[5]):
        raise ProtocolError('non_finite', 'sender_time')
    if not math.isfinite(sum(v[7:13]) + sum(v[14:20])):
        for o in (7, 14):                       # exact check (a finite sum may overflow)
            if not all(math.isfinite(x) for x in v[o:o + 6]):
                raise ProtocolError('non_finite', 'command field')
    return CommandPacket(v[4], v[5], v[6], (DeviceCommand(v[7:10], v[10:13], bool(v[13] & CMD_ENABLED)),
                                            DeviceCommand(v[14:17], v[17:20], bool(v[20] & CMD_ENABLED))))


def unpack_hello(data, mac):
    """-> (seq, sender_time, console_nonce); raises :class:`ProtocolError`."""
    _t, seq, sender_time, nonce = check_frame(data, mac, (TYPE_HELLO,))
    if nonce == 0 or not math.isfinite(sender_time):
        raise ProtocolError('session', 'console nonce 0 or non-finite time')
    return seq, sender_time, nonce


def unpack_challenge(data, mac):
    """-> :class:`Challenge`; raises :class:`ProtocolError`."""
    check_frame(data, mac, (TYPE_CHALLENGE,))
    v = _CHALLENGE_BODY.unpack_from(data)
    if v[6] == 0:
        raise ProtocolError('session', 'session nonce 0')
    return Challenge(v[4], v[5], v[6], v[7])


class SequenceTracker(object):
    """Accepts strictly increasing 32-bit sequence numbers (serial-number arithmetic, RFC 1982).

    ``accept(seq)`` returns the number of missing packets (gap) before ``seq`` when the packet is
    new, and raises :class:`ProtocolError` ('duplicate' or 'out_of_order') otherwise. ``reset()``
    forgets the last number so the next packet is accepted whatever its value (the receiver calls
    it after the link has been silent long enough for the console to have restarted).
    """

    HALF = 1 << 31
    MASK = 0xFFFFFFFF

    def __init__(self):
        self.last = None
        self.gaps = 0

    def reset(self):
        self.last = None

    def check(self, seq):
        """Return the gap ``seq`` would imply without changing state; raise if not new."""
        if self.last is None:
            return 0
        diff = (seq - self.last) & self.MASK
        if diff == 0:
            raise ProtocolError('duplicate', 'seq %d' % seq)
        if diff >= self.HALF:
            raise ProtocolError('out_of_order', 'seq %d after %d' % (seq, self.last))
        return diff - 1

    def accept(self, seq):
        gap = self.check(seq)
        self.last = seq & self.MASK
        self.gaps += gap
        return gap
