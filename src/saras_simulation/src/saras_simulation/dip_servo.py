"""The scripted surgeon's eyes: working height and tissue-contact dips (ROS-agnostic).

:class:`saras_simulation.touchball_console.ScriptedMotion` moves the handle along a path and, every
dip period, pushes it down. The teleoperation is incremental (the slave follows the master's
motion, scaled, from wherever it was when the clutch was last released; faults, clutch presses and
velocity limits lose motion), so an open-loop dip reaches the tissue only by chance. A surgeon
watches the endoscope instead. :class:`DipServo` does the same with the tool tip it is told about
(:meth:`observe`: tip position and signed distance ``sd`` to the tissue, from the simulator's
kinematics and tissue model). It keeps a persistent handle offset (master space):

* height ``e`` [m, downward]: ``de/dt = clip(gain * (sd - target), -speed, speed)`` with ``target``
  = ``hover`` [m] (working height above the tissue) between dips and from the start of a dip's
  ramp down, ``-depth`` (the tip pressed ``depth`` into the tissue) in the rest of the dip; within ``[-max_offset, max_offset]``. A surgeon works
  close to the tissue, so a dip has a short way to go;
* aim ``a`` [m, horizontal]: during a dip, moves the tip towards ``site`` (world x, y) with
  ``aim_gain``, at most half ``speed`` per axis, within ``max_aim``; kept after the dip, so the surgeon
  goes on working where the endoscope sees the contact.

Anti wind-up: the offsets move at most ``slack`` [m, master] away from an anchor, their values when
the tool was last seen following the handle: over the last ``follow_window`` [s] the tip moved along
the handle's motion (:meth:`handle`: the position the handle is given, path and offsets; scaled by
``scale``, master to slave) by at least ``follow_ratio`` of it, or, with the handle still,
the offsets are near the anchor (at rest) or the tip still moves towards them (catching up). A tool that does not follow
(teleoperation not engaged yet, held, clutched, set-points not executed) does not pull the handle away.

``speed`` is the pace the SARAS chain can follow on a loaded host: the teleoperation lets the
set-point lead the measured tip by only ``max_lead`` (3 mm, velocity_integrator) and reports a lead
saturated for ``max_stall`` (1 s) as "arm not following" (hold until the clutch); with a 0.3-0.5 s
set-point-to-measured-pose lag the slave may move at about 6 mm/s, i.e. ``speed`` 0.012 m/s of
handle at the 0.5 master-to-slave scale. The offsets change nothing of the slave's position by
themselves: motion the teleoperation loses (hold, clutch) is lost, and the servo corrects from what
it sees next.

A dip that begins before any observation is skipped (:meth:`update` returns None until it ends,
and ScriptedMotion then stays on its path: pushed blind, an open-loop dip drove a tool 27 mm into the
tissue while the platform started); with an observation older than ``timeout`` the offsets are held. Master and world axes are
taken as parallel (the Touch bases are aligned with ``world``); the gains absorb the master-to-slave
scale. Units: m, s.
"""
import collections
import math


def _clip(v, lo, hi):
    return lo if v < lo else hi if v > hi else v


class DipServo(object):
    """Working height and closed-loop dips: depth [m] target penetration, hover [m] working height
    above the tissue between dips (None: no offset between dips), site (x, y) [m] world target of
    the tip (None: no aiming), gain/aim_gain [1/s], speed [m/s] (master), max_offset/max_aim [m]
    (master), timeout [s] (observation age)."""

    def __init__(self, depth=0.003, site=None, hover=0.012, gain=2.0, aim_gain=1.0, speed=0.012,
                 max_offset=0.2, max_aim=0.08, timeout=0.5, slack=0.006, min_motion=0.001, scale=0.5,
                 follow_ratio=0.3, follow_window=1.0):
        for name, v in (('depth', depth), ('gain', gain), ('aim_gain', aim_gain), ('speed', speed),
                        ('max_offset', max_offset), ('max_aim', max_aim), ('timeout', timeout),
                        ('slack', slack), ('min_motion', min_motion), ('follow_window', follow_window),
                        ('scale', scale), ('follow_ratio', follow_ratio)) + (
                            () if hover is None else (('hover', hover),)):
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError('dip servo: %s must be finite and >= 0, got %r' % (name, v))
        if not scale > 0.0:
            raise ValueError('dip servo: scale must be > 0, got %r' % (scale,))
        if site is not None and (len(site) != 2 or not all(math.isfinite(s) for s in site)):
            raise ValueError('dip servo: site must be two finite numbers [m], got %r' % (site,))
        self.depth, self.gain, self.aim_gain, self.speed = float(depth), float(gain), float(aim_gain), float(speed)
        self.max_offset, self.max_aim, self.timeout = float(max_offset), float(max_aim), float(timeout)
        self.slack, self.min_motion = float(slack), float(min_motion)
        self.scale, self.follow_ratio, self.follow_window = float(scale), float(follow_ratio), float(follow_window)
        self.hover = None if hover is None else float(hover)
        self.site = None if site is None else (float(site[0]), float(site[1]))
        self._open = False      # this dip began without observation
        self._obs = None        # (t, tip (x, y, z), signed distance)
        self._t = None
        self._b, self._lifting = 0.0, False     # last dip weight; in the dip's ramp down
        self._anchor = (0.0, (0.0, 0.0))        # (offset, aim) when the tool was last seen following
        self._seen = collections.deque()        # (t, tip, handle) of the last follow_window s
        self._handle = None                     # latest handle position [m] (handle())
        self.offset = 0.0       # e [m] downward
        self.aim = (0.0, 0.0)   # a [m]

    def observe(self, t, tip, signed_distance):
        """Tip position (world, m) and its signed distance to the tissue [m] (> 0 above) at script time t."""
        if all(math.isfinite(v) for v in tuple(tip) + (signed_distance,)):
            self._obs = (float(t), tuple(float(v) for v in tip), float(signed_distance))
            if self._handle is not None:
                self._seen.append((self._obs[0], self._obs[1], self._handle))
            while self._seen and self._seen[0][0] < t - self.follow_window:
                self._seen.popleft()

    def fresh(self, t):
        return self._obs is not None and abs(t - self._obs[0]) <= self.timeout

    def update(self, t, b):
        """Advance to script time t with dip weight b in [0, 1]; returns (ax, ay, -e) to add to the
        handle position [m], or None before the first observation and in a dip that began before it
        (skipped)."""
        dt = 0.0 if self._t is None else _clip(t - self._t, 0.0, 0.05)
        self._t = t
        self._lifting = b > 0.0 and (self._lifting or b < self._b)     # the dip's ramp down
        self._b = b
        if b <= 0.0:
            self._open = False
        else:
            self._open = self._open or self._obs is None
        if self._open or self._obs is None:
            return None
        if not self.fresh(t):
            dt = 0.0                            # stale: hold the offsets
        _, tip, sd = self._obs
        step = self.speed * dt
        target = -self.depth if b > 0.0 and not self._lifting else self.hover
        if self._following():
            self._anchor = (self.offset, self.aim)
        lo, hi = self._anchor[0] - self.slack, self._anchor[0] + self.slack
        if target is not None:
            e = self.offset + _clip(self.gain * (sd - target) * dt, -step, step)
            self.offset = _clip(_clip(e, -self.max_offset, self.max_offset), min(lo, self.offset), max(hi, self.offset))
        if self.site is not None and b > 0.0:
            h = 0.5 * step                      # per axis: the aim and the height together stay within ~speed
            a = [_clip(a + _clip(self.aim_gain * (s - p) * dt, -h, h), min(r - self.slack, a), max(r + self.slack, a))
                 for a, r, s, p in zip(self.aim, self._anchor[1], self.site, tip[:2])]
            n = math.hypot(*a)
            self.aim = tuple(v * self.max_aim / n for v in a) if n > self.max_aim else tuple(a)
        return (self.aim[0], self.aim[1], -self.offset)

    def handle(self, position):
        """The handle position [m] (master) the offsets were added to this step: the anti wind-up's reference."""
        self._handle = tuple(position)

    def _following(self):
        """Over the last follow_window the tip followed the handle, or both were at rest (module doc)."""
        if len(self._seen) < 2:
            return False
        (_, tip0, h0), (_, tip1, h1) = self._seen[0], self._seen[-1]
        want = [self.scale * (b - a) for a, b in zip(h0, h1)]   # slave motion the handle asked for
        n = math.sqrt(sum(v * v for v in want))
        if n < self.min_motion:                 # handle still: at rest, or held at the anti wind-up limit
            (e0, a0) = self._anchor
            d = [self.aim[0] - a0[0], self.aim[1] - a0[1], e0 - self.offset]   # offsets since the anchor
            m = math.sqrt(sum(v * v for v in d))
            if m < 0.5 * self.slack:
                return True
            return sum((b - a) * v for a, b, v in zip(tip0, tip1, d)) / m >= self.min_motion   # catching up
        moved = sum((b - a) * v for a, b, v in zip(tip0, tip1, want)) / n
        return moved >= self.follow_ratio * n
