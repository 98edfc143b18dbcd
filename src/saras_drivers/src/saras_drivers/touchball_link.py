"""Touchball receiver core (ROS-agnostic): validation, filtering, watchdog, twist estimation.

The ROS adapter ``scripts/touchball_receiver`` owns the socket and the publishers; everything
that decides whether a datagram is accepted and what is published lives here so that it can be
tested without a roscore.

Units: metres, radians, seconds, newtons. Times passed as ``now`` are any monotonic clock [s].
"""

import math
from collections import namedtuple

from saras_drivers import touchball_protocol as tp

LinkSample = namedtuple('LinkSample', 'packet twists gap')
LinkSample.__doc__ = """An accepted state packet.

packet: :class:`touchball_protocol.StatePacket`; twists: per device ((vx, vy, vz) [m/s],
(wx, wy, wz) [rad/s]) in touch_<side>/base; gap: packets missing before this one."""


def quat_mul(a, b):
    """Hamilton product of quaternions (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def quat_conj(q):
    return (-q[0], -q[1], -q[2], q[3])


def quat_log_vec(q):
    """Rotation vector (axis * angle) [rad] of the unit quaternion q, shortest path."""
    x, y, z, w = q
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-12:
        return (2.0 * x, 2.0 * y, 2.0 * z)
    angle = 2.0 * math.atan2(s, w)
    return (x / s * angle, y / s * angle, z / s * angle)


class TwistEstimator(object):
    """Finite-difference twist of a pose stream, first-order low-pass filtered.

    Differences use the console's sender timestamps (they do not suffer the receive jitter).
    Angular velocity is expressed in the base frame: w = log(q_k * q_{k-1}^-1) / dt.

    :param cutoff_hz: low-pass cut-off [Hz]; <= 0 disables filtering.
    :param max_dt: a larger step between samples [s] restarts the estimator (twist 0).
    """

    def __init__(self, cutoff_hz=100.0, max_dt=0.1):
        self.tau = 1.0 / (2.0 * math.pi * cutoff_hz) if cutoff_hz > 0 else 0.0
        self.max_dt = max_dt
        self.reset()

    def reset(self):
        self._t = None
        self._p = self._q = None
        self.linear = (0.0, 0.0, 0.0)
        self.angular = (0.0, 0.0, 0.0)

    def update(self, t, position, orientation):
        """Feed a sample at sender time t [s]; returns (linear, angular)."""
        return self.update_flat(t, position[0], position[1], position[2], orientation[0],
                                orientation[1], orientation[2], orientation[3])

    def update_flat(self, t, px, py, pz, qx, qy, qz, qw):
        """:meth:`update` with scalar arguments (the receiver's hot path, no temporaries)."""
        if self._t is not None:
            dt = t - self._t
            if dt <= 0.0 or dt > self.max_dt:
                self.reset()
            else:
                ox, oy, oz = self._p
                ax, ay, az, aw = self._q
                # r = q * conj(q_prev): rotation from the previous to this orientation (base frame)
                rx = -qw * ax + qx * aw - qy * az + qz * ay
                ry = -qw * ay + qx * az + qy * aw - qz * ax
                rz = -qw * az - qx * ay + qy * ax + qz * aw
                rw = qw * aw + qx * ax + qy * ay + qz * az
                if rw < 0.0:
                    rx, ry, rz, rw = -rx, -ry, -rz, -rw
                s = math.sqrt(rx * rx + ry * ry + rz * rz)
                k = 2.0 if s < 1e-12 else 2.0 * math.atan2(s, rw) / s   # log: axis * angle
                a = dt / (dt + self.tau)
                b = a / dt
                lx, ly, lz = self.linear
                wx, wy, wz = self.angular
                self.linear = (lx + b * (px - ox) - a * lx,
                               ly + b * (py - oy) - a * ly, lz + b * (pz - oz) - a * lz)
                k *= b
                self.angular = (wx + k * rx - a * wx, wy + k * ry - a * wy, wz + k * rz - a * wz)
        self._p = (px, py, pz)
        self._q = (qx, qy, qz, qw)
        self._t = t
        return self.linear, self.angular


class TouchballLink(object):
    """Validates console datagrams and tracks the health of the link.

    :param allowed_source: IP address the console sends from; '' or '*' accepts any source.
    :param timeout: watchdog [s]: no valid packet for this long => stale (default 30 ms).
    :param resync_after: after this long [s] without a valid packet the sequence tracker is
        reset, so a restarted console (sequence back to 0) is accepted again -- provided its
        sender timestamp is newer than the last accepted one (replays stay refused).
    :param twist_cutoff_hz: twist low-pass cut-off [Hz].
    """

    def __init__(self, allowed_source='127.0.0.1', timeout=0.03, resync_after=1.0,
                 twist_cutoff_hz=100.0):
        if not timeout > 0.0:
            raise ValueError('timeout must be > 0 s, got %r' % (timeout,))
        if not resync_after >= timeout:
            raise ValueError('resync_after must be >= timeout, got %r' % (resync_after,))
        self.allowed_source = '' if allowed_source in (None, '', '*') else allowed_source
        self.timeout = float(timeout)
        self.resync_after = float(resync_after)
        self.sequence = tp.SequenceTracker()
        self.twist = [TwistEstimator(twist_cutoff_hz) for _ in tp.DEVICES]
        self.rejected = dict((r, 0) for r in tp.REJECT_REASONS)
        self.received = 0
        self.last_valid = None          # receive time of the last accepted packet
        self.last_error = ''
        # the last accepted packet, as decoded by touchball_protocol.decode_state
        self.seq = 0
        self.sender_time = None
        self.devices = None             # (left, right) flat (x, y, z, qx, qy, qz, qw, clip, buttons)
        self.gap = 0

    @property
    def rejected_total(self):
        return sum(self.rejected.values())

    @property
    def gaps(self):
        return self.sequence.gaps

    @property
    def last_packet(self):
        """The last accepted packet as a :class:`touchball_protocol.StatePacket` (None if none)."""
        if self.devices is None:
            return None
        return tp.StatePacket(self.seq, self.sender_time, tuple(tp.device_state(d) for d in self.devices))

    def twists(self):
        """Per device ((vx, vy, vz) [m/s], (wx, wy, wz) [rad/s]) of the last accepted packet."""
        return tuple((est.linear, est.angular) for est in self.twist)

    def accept(self, data, source_ip, now):
        """Validate one datagram received from ``source_ip`` at ``now`` [s] (hot path).

        Returns True when accepted: ``seq``, ``sender_time``, ``devices``, ``gap`` and each
        ``twist[i].linear/angular`` then describe it. Returns False otherwise: the rejection is
        counted in ``rejected[reason]`` and described in ``last_error``. Never raises on bad input.
        """
        try:
            if self.allowed_source and source_ip != self.allowed_source:
                raise tp.ProtocolError('foreign_source', str(source_ip))
            seq, sender_time, left, right = tp.decode_state(data)
            if self.last_valid is not None and now - self.last_valid > self.resync_after:
                # The console may have restarted (sequence back to 0): accept a new sequence,
                # but only with a newer sender timestamp, so an old packet replayed after a
                # silence is still refused.
                if sender_time <= self.sender_time:
                    raise tp.ProtocolError('out_of_order', 'sender_time %.6f not newer than %.6f '
                                           'after resync' % (sender_time, self.sender_time))
                self.sequence.reset()
                for est in self.twist:
                    est.reset()
            self.gap = self.sequence.accept(seq)
        except tp.ProtocolError as e:
            self.rejected[e.reason] += 1
            self.last_error = str(e)
            return False
        except (TypeError, ValueError) as e:     # not a bytes-like object: counted as a size error
            self.rejected['size'] += 1
            self.last_error = 'size: %s' % e
            return False
        self.twist[0].update_flat(sender_time, *left[:7])
        self.twist[1].update_flat(sender_time, *right[:7])
        self.received += 1
        self.last_valid = now
        self.seq, self.sender_time, self.devices = seq, sender_time, (left, right)
        return True

    def handle_datagram(self, data, source_ip, now):
        """Validate one datagram received from ``source_ip`` at ``now`` [s].

        Returns a :class:`LinkSample` when accepted, else None (the rejection is counted in
        ``rejected[reason]`` and described in ``last_error``). Never raises on bad input.
        Convenience wrapper of :meth:`accept` (which the receiver uses, without the tuples).
        """
        if not self.accept(data, source_ip, now):
            return None
        return LinkSample(self.last_packet, self.twists(), self.gap)

    def input_age(self, now):
        """Seconds since the last valid packet (inf if none yet)."""
        return float('inf') if self.last_valid is None else now - self.last_valid

    def is_stale(self, now):
        return self.input_age(now) > self.timeout


class WrenchLatch(object):
    """Latest force command of one device, validated, clamped and aged.

    A command older than ``max_age`` [s] or never received yields a disabled zero command, so a
    dead teleoperation never leaves a force on the user's hand. Non-finite commands are rejected
    (counted) and the latch falls back to zero force.

    :param max_force: clamp of |force| [N] (Touch: 3.3 N peak).
    :param max_torque: clamp of |torque| [N m] (the Touch has no torque actuation: default 0).
    """

    def __init__(self, max_force=3.3, max_torque=0.0, max_age=0.1):
        if not max_force >= 0.0 or not max_torque >= 0.0 or not max_age > 0.0:
            raise ValueError('max_force, max_torque must be >= 0 and max_age > 0')
        self.max_force = float(max_force)
        self.max_torque = float(max_torque)
        self.max_age = float(max_age)
        self.rejected = 0
        self._cmd = tp.ZERO_COMMAND
        self._stamp = None

    @staticmethod
    def _clamp(v, limit):
        n = math.sqrt(sum(x * x for x in v))
        if n > limit:
            s = limit / n if n > 0.0 else 0.0
            return tuple(x * s for x in v)
        return tuple(v)

    def set(self, force, torque, now):
        """Store a command received at ``now``; returns False (and zeroes) if not finite."""
        if not all(math.isfinite(x) for x in tuple(force) + tuple(torque)):
            self.rejected += 1
            self._cmd, self._stamp = tp.ZERO_COMMAND, None
            return False
        self._cmd = tp.DeviceCommand(self._clamp(force, self.max_force),
                                     self._clamp(torque, self.max_torque), True)
        self._stamp = now
        return True

    def get(self, now):
        if self._stamp is None or now - self._stamp > self.max_age:
            return tp.ZERO_COMMAND
        return self._cmd
