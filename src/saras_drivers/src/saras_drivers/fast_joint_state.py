"""sensor_msgs/JointState with a fixed joint list, serialised without re-encoding the names.

genpy's JointState.serialize encodes and packs every joint name of every message (13 names: most of
the 14 us a SARAS arm's joint_states message costs, 300 times a second). :class:`FastJointState`
keeps the serialised ``frame_id`` and ``name`` part and rebuilds it only when either changes; the
bytes are those of ``JointState.serialize`` (pytest). A message with velocities or efforts is
serialised by the generated code.
"""
import struct

from sensor_msgs.msg import JointState

_HEADER = struct.Struct('<3I')
_EMPTY_VELOCITY_EFFORT = struct.pack('<II', 0, 0)


def _string(s):
    b = s.encode('utf-8')
    return struct.pack('<I', len(b)) + b


class FastJointState(JointState):
    # no __slots__ here: genpy's generic methods read the message fields from self.__slots__
    def __init__(self, *args, **kwargs):
        super(FastJointState, self).__init__(*args, **kwargs)
        self._frame, self._names, self._middle = None, None, b''
        self._positions = (None, None)        # (count, struct '<I' + count doubles)

    def serialize(self, buff):
        if self.velocity or self.effort:
            return super(FastJointState, self).serialize(buff)
        try:
            if self.header.frame_id != self._frame or self.name != self._names:
                self._middle = _string(self.header.frame_id) + struct.pack('<I', len(self.name)) + \
                    b''.join(_string(n) for n in self.name)
                self._frame, self._names = self.header.frame_id, list(self.name)
            n = len(self.position)
            if self._positions[0] != n:
                self._positions = (n, struct.Struct('<I%dd' % n))
            s = self.header.stamp
            buff.write(_HEADER.pack(self.header.seq, s.secs, s.nsecs))
            buff.write(self._middle)
            buff.write(self._positions[1].pack(n, *self.position))
            buff.write(_EMPTY_VELOCITY_EFFORT)
        except (struct.error, TypeError, AttributeError) as e:
            self._check_types(ValueError('%s: %s' % (type(e).__name__, e)))
