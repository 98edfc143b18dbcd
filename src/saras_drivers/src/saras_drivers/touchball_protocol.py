"""Touchball console link: the versioned UDP packet formats (protocol version 1).

This module is the ONE implementation of the wire format. The console simulator, the ROS
receiver, the tests and the benchmarks all use it. It has no ROS dependency.

All fields are little-endian. See ``docs/touchball_protocol.md`` for the normative description.

State packet (console -> ROS), 160 bytes::

    header   magic 'TBAL' (4s) | version u8 | type u8 (1 = STATE) | flags u16 | seq u32 | sender_time f64 [s]
    device x2 (left, then right), 68 bytes each:
             position 3 x f64 [m] in touch_<side>/base (z up, x away from the user, y left)
             orientation quaternion 4 x f64 (x, y, z, w), unit norm
             clip_angle f64 [rad] (after the console's clip-range calibration)
             buttons u32 bit mask (bit 0 clutch, bit 1 clip button, other bits 0)
    crc32    u32 = zlib.crc32 of every preceding byte

Command packet (ROS -> console), 128 bytes::

    header   same layout, type u8 = 2 (COMMAND); seq and sender_time are the ROS side's
    device x2 (left, then right), 52 bytes each:
             force 3 x f64 [N] and torque 3 x f64 [N m] in touch_<side>/base
             flags u32 (bit 0 ENABLED: 0 means "apply zero force")
    crc32    u32
"""

import math
import struct
import zlib
from collections import namedtuple

MAGIC = b'TBAL'
VERSION = 1
TYPE_STATE = 1
TYPE_COMMAND = 2

DEVICES = ('left', 'right')

BUTTON_CLUTCH = 0x1
BUTTON_CLIP = 0x2
CMD_ENABLED = 0x1

HEADER = struct.Struct('<4sBBHId')
STATE_DEVICE = struct.Struct('<3d4ddI')
COMMAND_DEVICE = struct.Struct('<3d3dI')
CRC = struct.Struct('<I')

STATE_SIZE = HEADER.size + 2 * STATE_DEVICE.size + CRC.size
COMMAND_SIZE = HEADER.size + 2 * COMMAND_DEVICE.size + CRC.size

# Whole-packet layouts (everything before the CRC) for the single-call hot paths.
_STATE_BODY = struct.Struct('<4sBBHId3d4ddI3d4ddI')
_COMMAND_BODY = struct.Struct('<4sBBHId3d3dI3d3dI')
_STATE_PREFIX = MAGIC + bytes((VERSION, TYPE_STATE))
assert _STATE_BODY.size + CRC.size == STATE_SIZE and _COMMAND_BODY.size + CRC.size == COMMAND_SIZE

#: Accepted deviation of the quaternion norm from 1 before a packet is rejected.
QUATERNION_NORM_TOLERANCE = 1e-3

#: Reasons a datagram can be rejected; every rejection is counted under exactly one of them.
REJECT_REASONS = ('foreign_source', 'size', 'magic', 'version', 'type', 'crc', 'non_finite',
                  'quaternion', 'duplicate', 'out_of_order')

DeviceState = namedtuple('DeviceState', 'position orientation clip_angle clutch clip_button')
DeviceState.__doc__ = """One device in a state packet.

position: (x, y, z) [m]; orientation: (x, y, z, w) unit quaternion; clip_angle [rad];
clutch, clip_button: bool."""

StatePacket = namedtuple('StatePacket', 'seq sender_time devices')
StatePacket.__doc__ = "Decoded state packet: seq (u32), sender_time [s], devices (left, right)."

DeviceCommand = namedtuple('DeviceCommand', 'force torque enabled')
DeviceCommand.__doc__ = "force (3) [N], torque (3) [N m] in touch_<side>/base, enabled (bool)."

CommandPacket = namedtuple('CommandPacket', 'seq sender_time devices')

ZERO_COMMAND = DeviceCommand((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), False)


class ProtocolError(ValueError):
    """A datagram that is not a valid packet; ``reason`` is one of :data:`REJECT_REASONS`."""

    def __init__(self, reason, detail=''):
        super(ProtocolError, self).__init__('%s: %s' % (reason, detail) if detail else reason)
        self.reason = reason


def _finish(body):
    return body + CRC.pack(zlib.crc32(body) & 0xFFFFFFFF)


def pack_state(seq, sender_time, devices):
    """Encode a state packet. ``devices`` = (left, right) :class:`DeviceState`. Returns bytes."""
    if len(devices) != 2:
        raise ValueError('a state packet carries exactly two devices')
    (lp, lq, lc, lcl, lcb), (rp, rq, rc, rcl, rcb) = devices
    body = _STATE_BODY.pack(MAGIC, VERSION, TYPE_STATE, 0, seq & 0xFFFFFFFF, float(sender_time),
                            lp[0], lp[1], lp[2], lq[0], lq[1], lq[2], lq[3], lc,
                            (BUTTON_CLUTCH if lcl else 0) | (BUTTON_CLIP if lcb else 0),
                            rp[0], rp[1], rp[2], rq[0], rq[1], rq[2], rq[3], rc,
                            (BUTTON_CLUTCH if rcl else 0) | (BUTTON_CLIP if rcb else 0))
    return body + CRC.pack(zlib.crc32(body) & 0xFFFFFFFF)


def pack_command(seq, sender_time, commands):
    """Encode a command packet. ``commands`` = (left, right) :class:`DeviceCommand`."""
    if len(commands) != 2:
        raise ValueError('a command packet carries exactly two devices')
    (lf, lt, le), (rf, rt, re) = commands
    body = _COMMAND_BODY.pack(MAGIC, VERSION, TYPE_COMMAND, 0, seq & 0xFFFFFFFF, float(sender_time),
                              lf[0], lf[1], lf[2], lt[0], lt[1], lt[2], CMD_ENABLED if le else 0,
                              rf[0], rf[1], rf[2], rt[0], rt[1], rt[2], CMD_ENABLED if re else 0)
    return body + CRC.pack(zlib.crc32(body) & 0xFFFFFFFF)


def _check_frame(data, size, ptype):
    """Validate size, magic, version, type and CRC. Returns the decoded header tuple."""
    if len(data) != size:
        raise ProtocolError('size', 'got %d bytes, expected %d' % (len(data), size))
    magic, version, t, _flags, seq, sender_time = HEADER.unpack_from(data, 0)
    if magic != MAGIC:
        raise ProtocolError('magic', repr(magic))
    if version != VERSION:
        raise ProtocolError('version', 'got %d, expected %d' % (version, VERSION))
    if t != ptype:
        raise ProtocolError('type', 'got %d, expected %d' % (t, ptype))
    (crc,) = CRC.unpack_from(data, size - CRC.size)
    if crc != (zlib.crc32(memoryview(data)[:size - CRC.size]) & 0xFFFFFFFF):
        raise ProtocolError('crc')
    if not math.isfinite(sender_time):
        raise ProtocolError('non_finite', 'sender_time')
    return seq, sender_time


def decode_state(data):
    """Decode and validate a state packet with one ``struct`` call (the receiver's hot path).

    Returns ``(seq, sender_time, left, right)`` where each device is the flat tuple
    ``(x, y, z, qx, qy, qz, qw, clip_angle, buttons)`` [m, unit quaternion, rad, bit mask] with the
    quaternion re-normalised. Raises :class:`ProtocolError`; checks in this order, the first
    failing one is the reason: size, magic, version, type, crc, non_finite (any field, sender
    time first), quaternion (left, then right). The defective cases fall back to field-by-field
    checks, so the fast path costs one unpack, one CRC and two sums.
    """
    if (len(data) != STATE_SIZE or data[:6] != _STATE_PREFIX
            or CRC.unpack_from(data, STATE_SIZE - CRC.size)[0]
            != zlib.crc32(memoryview(data)[:STATE_SIZE - CRC.size])):
        _check_frame(data, STATE_SIZE, TYPE_STATE)      # raises the precise reason
    v = _STATE_BODY.unpack_from(data)
    # v: magic, version, type, flags, seq, sender_time, left (8 floats, buttons), right (...)
    if not math.isfinite(v[5] + sum(v[6:14]) + sum(v[15:23])):
        _check_finite(v)                                # raises (or a finite overflow: passes)
    out = [v[4], v[5]]
    for o in (6, 15):
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
    for o in (6, 15):
        if not all(math.isfinite(x) for x in v[o:o + 8]):
            raise ProtocolError('non_finite', 'device field')


def device_state(flat):
    """:class:`DeviceState` of one flat device tuple returned by :func:`decode_state`."""
    return DeviceState(flat[0:3], flat[3:7], flat[7], bool(flat[8] & BUTTON_CLUTCH),
                       bool(flat[8] & BUTTON_CLIP))


def unpack_state(data):
    """Decode and validate a state packet; raises :class:`ProtocolError` on any defect.

    The quaternion must have a norm within :data:`QUATERNION_NORM_TOLERANCE` of 1; it is
    returned re-normalised.
    """
    seq, sender_time, left, right = decode_state(data)
    return StatePacket(seq, sender_time, (device_state(left), device_state(right)))


def unpack_command(data):
    """Decode and validate a command packet; raises :class:`ProtocolError` on any defect."""
    seq, sender_time = _check_frame(data, COMMAND_SIZE, TYPE_COMMAND)
    v = _COMMAND_BODY.unpack_from(data)
    # v: header (6), left force (3), torque (3), flags, right force, torque, flags
    if not math.isfinite(sum(v[6:12]) + sum(v[13:19])):
        for o in (6, 13):                       # exact check (a finite sum may overflow)
            if not all(math.isfinite(x) for x in v[o:o + 6]):
                raise ProtocolError('non_finite', 'command field')
    return CommandPacket(seq, sender_time, (DeviceCommand(v[6:9], v[9:12], bool(v[12] & CMD_ENABLED)),
                                            DeviceCommand(v[13:16], v[16:19], bool(v[19] & CMD_ENABLED))))


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
