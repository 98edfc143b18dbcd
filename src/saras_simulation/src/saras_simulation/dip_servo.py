"""The scripted surgeon's eyes during a tissue-contact dip (ROS-agnostic).

:class:`saras_simulation.touchball_console.ScriptedMotion` pushes the handle down during a dip. The
teleoperation is incremental (the slave follows the master's motion, scaled, from wherever it was
when the clutch was last released; faults, clutch presses and velocity limits lose motion), so an
open-loop dip reaches the tissue only by chance: depending on the script phase at which the
teleoperation engaged and on the motion lost since, the tool stops centimetres above the tissue
or pushes a centimetre into it. A surgeon watches the endoscope instead. :class:`DipServo` does the
same with the tool tip it is told about (:meth:`observe`: tip position and signed distance to the
tissue, from the simulator's kinematics and tissue model):

* depth: the handle's dip offset ``e`` [m, master space, downward] is a rate-limited servo on the
  tip's signed distance ``sd`` to the target penetration: ``de/dt = clip(gain * (sd + depth),
  -speed, speed)``, kept within ``[0, b * max_offset]`` (b: the dip's blend weight, so the dip
  still starts and ends smoothly) and within ``slack`` of what the tip has followed (its descent
  since the dip began, divided by the expected master-to-slave ``scale``): a tool that does not
  follow (teleoperation not engaged, held, clutched) does not wind the handle down;
* aim: the handle's horizontal offset ``a`` moves the tip towards ``site`` (world x, y) with the
  same law (``aim_gain``), kept within ``b * max_aim`` (and half the slack of what the tip followed),
  so that the contact happens where the
  endoscope sees it.

A dip that begins before any observation stays open loop (:meth:`update` returns None); with an
observation older than ``timeout`` the offsets are held.
Master and world axes are taken as parallel (the Touch bases are aligned with ``world``); the
gains absorb the master-to-slave scale. Units: m, s.
"""
import math


def _clip(v, lo, hi):
    return lo if v < lo else hi if v > hi else v


class DipServo(object):
    """Closed-loop dip: depth [m] target penetration, site (x, y) [m] world target of the tip (None:
    no aiming), gain/aim_gain [1/s], speed [m/s] (master), max_offset/max_aim [m] (master),
    timeout [s] (observation age)."""

    def __init__(self, depth=0.003, site=None, gain=3.0, aim_gain=1.5, speed=0.06, max_offset=0.2,
                 max_aim=0.08, timeout=0.5, scale=0.5, slack=0.04):
        for name, v in (('depth', depth), ('gain', gain), ('aim_gain', aim_gain), ('speed', speed),
                        ('max_offset', max_offset), ('max_aim', max_aim), ('timeout', timeout),
                        ('scale', scale), ('slack', slack)):
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError('dip servo: %s must be finite and >= 0, got %r' % (name, v))
        if site is not None and (len(site) != 2 or not all(math.isfinite(s) for s in site)):
            raise ValueError('dip servo: site must be two finite numbers [m], got %r' % (site,))
        self.depth, self.gain, self.aim_gain, self.speed = float(depth), float(gain), float(aim_gain), float(speed)
        self.max_offset, self.max_aim, self.timeout = float(max_offset), float(max_aim), float(timeout)
        if not scale > 0.0:
            raise ValueError('dip servo: scale must be > 0, got %r' % scale)
        self.scale, self.slack = float(scale), float(slack)
        self._top = None        # highest tip z [m] seen in this dip
        self._start = None      # tip (x, y) [m] when this dip was first seen
        self._open = False      # this dip began without observation
        self.site = None if site is None else (float(site[0]), float(site[1]))
        self._obs = None        # (t, tip (x, y, z), signed distance)
        self._t = None
        self.offset = 0.0       # e [m] downward
        self.aim = (0.0, 0.0)   # a [m]

    def observe(self, t, tip, signed_distance):
        """Tip position (world, m) and its signed distance to the tissue [m] (> 0 above) at script time t."""
        if all(math.isfinite(v) for v in tuple(tip) + (signed_distance,)):
            self._obs = (float(t), tuple(float(v) for v in tip), float(signed_distance))

    def fresh(self, t):
        return self._obs is not None and abs(t - self._obs[0]) <= self.timeout

    def update(self, t, b):
        """Advance to script time t with dip weight b in [0, 1]; returns (ax, ay, -e) to add to the
        handle position [m], or None in a dip that began before the first observation (open loop)."""
        dt = 0.0 if self._t is None else _clip(t - self._t, 0.0, 0.05)
        self._t = t
        if b <= 0.0:
            self.offset, self.aim, self._top, self._start = 0.0, (0.0, 0.0), None, None
            self._open = False
            return None
        self._open = self._open or self._obs is None
        if self._open:                          # a dip begun blind stays open loop to its end
            return None
        if not self.fresh(t):
            dt = 0.0                            # stale: hold the offsets
        _, tip, sd = self._obs
        step = self.speed * dt
        self._top = tip[2] if self._top is None else max(self._top, tip[2])
        e = self.offset + _clip(self.gain * (sd + self.depth) * dt, -step, step)
        followed = (self._top - tip[2]) / self.scale + self.slack
        self.offset = _clip(e, 0.0, min(b * self.max_offset, max(followed, self.offset - step)))
        if self.site is not None:
            self._start = self._start or tip[:2]
            lim = b * self.max_aim
            a = [_clip(a + _clip(self.aim_gain * (s - p) * dt, -step, step), -lim, lim)
                 for a, s, p in zip(self.aim, self.site, tip[:2])]
            n, allowed = math.hypot(*a), math.hypot(tip[0] - self._start[0], tip[1] - self._start[1]) / self.scale
            allowed = max(allowed + self.slack / 2, math.hypot(*self.aim) - step)
            self.aim = tuple(v * allowed / n for v in a) if n > allowed else tuple(a)
        return (self.aim[0], self.aim[1], -self.offset)
