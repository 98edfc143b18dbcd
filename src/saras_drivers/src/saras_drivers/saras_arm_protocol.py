"""SARAS arm Socket.IO protocol (version 1): event names, payload schemas and validation.

ONE module shared by the simulator (server) and the ROS driver/state nodes (clients). No ROS
dependency. See ``docs/saras_arm_protocol.md`` for the normative description.

All quantities are SI: metres, radians, seconds. Poses are in the robot base frame
(``mesa_<side>/sbs_world``, the centre of the Positioning-Arm base). Quaternions are
[x, y, z, w]. The joint vector is the 6 motor joints
``er_yaw, er_pitch, er_insertion, er_roll, adapter_roll, jaw`` (see :data:`MOTOR_JOINTS`).

Client -> server events (the server answers every one with a Socket.IO acknowledgement
``{"ok": bool, "code": str, "message": str, "id": int}``; a rejected command also triggers an
``error`` event so that fire-and-forget clients see it):

``set_target``       ``{"id": int, "position": [x, y, z], "orientation": [x, y, z, w] | null,
                     "time": float}`` (``time``, optional: sender wall clock [s]; a server with
                     ``max_target_age`` drops targets older than that when it executes them,
                     counted, no ``error`` event; one behind which a newer ``set_target`` is
                     already waiting is skipped: ``superseded``, counted, no ``error`` event)
``set_max_velocity`` ``{"id": int, "max_velocity": float}``      [rad/s]; insertion moves at
                     max_velocity * insertion_ratio [m/s] (ratio published in ``info``)
``set_clip``         ``{"id": int, "jaw": float | null, "roll": float | null, "time": float}``   [rad],
                     null = keep; ``time`` optional, as for ``set_target``
``hold``             ``{"id": int}``  stop: target := current joints
``subscribe_state``  ``{"window": int}`` (optional) join the ``state`` stream (the ack carries
                     ``info``); with ``window`` >= 1 the server keeps at most that many states
                     in flight to this client (sent, not yet reported received by ``state_ack``)
                     and skips samples beyond it, so a reader slower than the stream gets recent
                     states instead of a growing backlog
``state_ack``        ``{"received": int}`` states received on this connection so far (no answer)

Server -> client events:

``state``  ``{"seq": int, "time": float, "joints": [6], "ee_position": [3], "ee_orientation": [4],
           "rcm_position": [3], "moving": bool, "max_velocity": float, "target_id": int}``
``error``  ``{"id": int, "event": str, "code": str, "message": str}``
"""

import math

VERSION = 1
NAMESPACE = '/'

EV_SET_TARGET = 'set_target'
EV_SET_MAX_VELOCITY = 'set_max_velocity'
EV_SET_CLIP = 'set_clip'
EV_HOLD = 'hold'
EV_SUBSCRIBE_STATE = 'subscribe_state'
EV_STATE_ACK = 'state_ack'
EV_STATE = 'state'
EV_ERROR = 'error'
STATE_ROOM = 'state'

MOTOR_JOINTS = ('er_yaw', 'er_pitch', 'er_insertion', 'er_roll', 'adapter_roll', 'jaw')

# Result codes (``code`` field).
OK = 'ok'
BAD_PAYLOAD = 'bad_payload'          # missing field, wrong type, wrong length, non-finite
RCM_VIOLATION = 'rcm_violation'      # target not reachable by pivoting through the RCM
WORKSPACE = 'workspace'              # pivot angles / insertion / clip beyond joint limits
BAD_VALUE = 'bad_value'              # e.g. max velocity <= 0 or above the hardware limit
STALE = 'stale'                      # set_target older than the server's max_target_age
SUPERSEDED = 'superseded'            # set_target not executed: a newer one was already waiting
NOT_COMMANDER = 'not_commander'      # from a session that is not the authenticated commanding one
RATE_LIMITED = 'rate_limited'        # the session sent more events than its rate limit
CODES = (OK, BAD_PAYLOAD, RCM_VIOLATION, WORKSPACE, BAD_VALUE, STALE, SUPERSEDED, NOT_COMMANDER, RATE_LIMITED)

#: Largest Engine.IO message the server accepts [bytes] (a command is ~150 bytes).
MAX_MESSAGE_BYTES = 4096
#: Fields each client event may carry (anything else: bad_payload).
FIELDS = {'set_target': {'id', 'position', 'orientation', 'time'},
          'set_max_velocity': {'id', 'max_velocity'}, 'set_clip': {'id', 'jaw', 'roll', 'time'},
          'hold': {'id'}, 'subscribe_state': {'window'}, 'state_ack': {'received'}}


class ProtocolError(ValueError):
    """A payload that does not follow the schema; ``code`` is one of :data:`CODES`."""

    def __init__(self, code, message):
        super(ProtocolError, self).__init__('%s: %s' % (code, message))
        self.code = code
        self.message = message


def reply(ok, code=OK, message='', cmd_id=0):
    return {'ok': bool(ok), 'code': code, 'message': message, 'id': int(cmd_id)}


def _id(payload):
    v = payload.get('id', 0)
    if isinstance(v, bool) or not isinstance(v, int) or not -2 ** 63 <= v < 2 ** 63:
        raise ProtocolError(BAD_PAYLOAD, 'id must be a 64-bit integer')
    return v


def _known(payload, event):
    """Refuse fields the event does not define."""
    extra = set(payload) - FIELDS[event]
    if extra:
        raise ProtocolError(BAD_PAYLOAD, 'unknown field(s) %s' % ', '.join(sorted(str(k)[:32] for k in extra)))
    return payload


def _vector(payload, key, n, optional=False):
    v = payload.get(key)
    if v is None:
        if optional:
            return None
        raise ProtocolError(BAD_PAYLOAD, '%s missing' % key)
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise ProtocolError(BAD_PAYLOAD, '%s must be a list of %d numbers' % (key, n))
    out = []
    for x in v:
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            raise ProtocolError(BAD_PAYLOAD, '%s must hold finite numbers' % key)
        out.append(float(x))
    return tuple(out)


def _scalar(payload, key, optional=False):
    v = payload.get(key)
    if v is None:
        if optional:
            return None
        raise ProtocolError(BAD_PAYLOAD, '%s missing' % key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ProtocolError(BAD_PAYLOAD, '%s must be a finite number' % key)
    return float(v)


def _dict(payload):
    if not isinstance(payload, dict):
        raise ProtocolError(BAD_PAYLOAD, 'payload must be an object')
    return payload


def make_set_target(cmd_id, position, orientation=None, t=None):
    d = {'id': int(cmd_id), 'position': [float(x) for x in position], 'orientation': None}
    if orientation is not None:
        d['orientation'] = [float(x) for x in orientation]
    if t is not None:
        d['time'] = float(t)
    return d


def target_time(payload):
    """The optional ``time`` of a ``set_target`` or ``set_clip`` [s, sender wall clock], or None."""
    return _scalar(_dict(payload), 'time', optional=True)


def parse_set_target(payload):
    """-> (id, position (3), orientation (4, normalised) or None)."""
    p = _known(_dict(payload), EV_SET_TARGET)
    cmd_id = _id(p)
    pos = _vector(p, 'position', 3)
    _scalar(p, 'time', optional=True)          # validated here; read with target_time()
    q = _vector(p, 'orientation', 4, optional=True)
    if q is not None:
        n = math.sqrt(sum(x * x for x in q))
        if abs(n - 1.0) > 1e-3:
            raise ProtocolError(BAD_PAYLOAD, 'orientation must be a unit quaternion (norm %g)' % n)
        q = tuple(x / n for x in q)
    return cmd_id, pos, q


def make_set_max_velocity(cmd_id, max_velocity):
    return {'id': int(cmd_id), 'max_velocity': float(max_velocity)}


def parse_set_max_velocity(payload):
    p = _known(_dict(payload), EV_SET_MAX_VELOCITY)
    return _id(p), _scalar(p, 'max_velocity')


def make_set_clip(cmd_id, jaw=None, roll=None, t=None):
    nan_to_none = lambda v: None if v is None or (isinstance(v, float) and math.isnan(v)) else float(v)
    d = {'id': int(cmd_id), 'jaw': nan_to_none(jaw), 'roll': nan_to_none(roll)}
    if t is not None:
        d['time'] = float(t)
    return d


def parse_set_clip(payload):
    """-> (id, jaw or None, roll or None)."""
    p = _known(_dict(payload), EV_SET_CLIP)
    _scalar(p, 'time', optional=True)          # validated here; read with target_time()
    return _id(p), _scalar(p, 'jaw', optional=True), _scalar(p, 'roll', optional=True)


def parse_hold(payload):
    return _id(_known(_dict(payload or {}), EV_HOLD))


def _count(payload, key):
    v = _dict(payload).get(key)
    if not isinstance(v, int) or isinstance(v, bool) or not 0 <= v < 2 ** 63:
        raise ProtocolError(BAD_PAYLOAD, '%s must be an integer >= 0, got %r' % (key, v))
    return v


def parse_subscribe_state(payload):
    """:return: the flow-control window [states] (0 = none: every sample is sent)."""
    if payload is None or payload == {}:
        return 0
    if _known(_dict(payload), EV_SUBSCRIBE_STATE).get('window') is None:
        return 0
    return _count(payload, 'window')


def parse_state_ack(payload):
    """:return: the number of states the client received on this connection."""
    return _count(_known(_dict(payload), EV_STATE_ACK), 'received')


def make_state(seq, t, joints, ee_position, ee_orientation, rcm_position, moving, max_velocity,
               target_id):
    return {'seq': int(seq), 'time': float(t), 'joints': [float(x) for x in joints],
            'ee_position': [float(x) for x in ee_position],
            'ee_orientation': [float(x) for x in ee_orientation],
            'rcm_position': [float(x) for x in rcm_position], 'moving': bool(moving),
            'max_velocity': float(max_velocity), 'target_id': int(target_id)}


def parse_state(payload):
    """Validate a ``state`` event; returns a dict with tuples of floats."""
    p = _dict(payload)
    out = {'seq': _id({'id': p.get('seq', -1)}), 'time': _scalar(p, 'time'),
           'joints': _vector(p, 'joints', len(MOTOR_JOINTS)),
           'ee_position': _vector(p, 'ee_position', 3),
           'ee_orientation': _vector(p, 'ee_orientation', 4),
           'rcm_position': _vector(p, 'rcm_position', 3),
           'moving': bool(p.get('moving', False)),
           'max_velocity': _scalar(p, 'max_velocity'),
           'target_id': _id({'id': p.get('target_id', 0)})}
    return out
