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
    parts = [HEADER.pack(MAGIC, VERSION, TYPE_STATE, 0, seq & 0xFFFFFFFF, float(sender_time))]
    for d in devices:
        buttons = (BUTTON_CLUTCH if d.clutch else 0) | (BUTTON_CLIP if d.clip_button else 0)
        parts.append(STATE_DEVICE.pack(d.position[0], d.position[1], d.position[2],
                                       d.orientation[0], d.orientation[1], d.orientation[2],
                                       d.orientation[3], d.clip_angle, buttons))
    if len(parts) != 3:
        raise ValueError('a state packet carries exactly two devices')
    return _finish(b''.join(parts))


def pack_command(seq, sender_time, commands):
    """Encode a command packet. ``commands`` = (left, right) :class:`DeviceCommand`."""
    parts = [HEADER.pack(MAGIC, VERSION, TYPE_COMMAND, 0, seq & 0xFFFFFFFF, float(sender_time))]
    for c in commands:
        parts.append(COMMAND_DEVICE.pack(c.force[0], c.force[1], c.force[2],
                                         c.torque[0], c.torque[1], c.torque[2],
                                         CMD_ENABLED if c.enabled else 0))
    if len(parts) != 3:
        raise ValueError('a command packet carries exactly two devices')
    return _finish(b''.join(parts))


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


def unpack_state(data):
    """Decode and validate a state packet; raises :class:`ProtocolError` on any defect.

    The quaternion must have a norm within :data:`QUATERNION_NORM_TOLERANCE` of 1; it is
    returned re-normalised.
    """
    seq, sender_time = _check_frame(data, STATE_SIZE, TYPE_STATE)
    devices = []
    off = HEADER.size
    for _ in DEVICES:
        v = STATE_DEVICE.unpack_from(data, off)
        off += STATE_DEVICE.size
        if not all(math.isfinite(x) for x in v[:8]):
            raise ProtocolError('non_finite', 'device field')
        q = v[3:7]
        n = math.sqrt(sum(x * x for x in q))
        if abs(n - 1.0) > QUATERNION_NORM_TOLERANCE:
            raise ProtocolError('quaternion', 'norm %g' % n)
        devices.append(DeviceState(v[0:3], tuple(x / n for x in q), v[7],
                                   bool(v[8] & BUTTON_CLUTCH), bool(v[8] & BUTTON_CLIP)))
    return StatePacket(seq, sender_time, tuple(devices))


def unpack_command(data):
    """Decode and validate a command packet; raises :class:`ProtocolError` on any defect."""
    seq, sender_time = _check_frame(data, COMMAND_SIZE, TYPE_COMMAND)
    cmds = []
    off = HEADER.size
    for _ in DEVICES:
        v = COMMAND_DEVICE.unpack_from(data, off)
        off += COMMAND_DEVICE.size
        if not all(math.isfinite(x) for x in v[:6]):
            raise ProtocolError('non_finite', 'command field')
        cmds.append(DeviceCommand(v[0:3], v[3:6], bool(v[6] & CMD_ENABLED)))
    return CommandPacket(seq, sender_time, tuple(cmds))


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
