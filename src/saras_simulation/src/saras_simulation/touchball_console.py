"""Touchball console simulator core (ROS-agnostic): emulates the Windows Touchball controller.

Pieces (each testable alone):

* :class:`ScriptedMotion` -- the assistant surgeon's intended handle motion (smooth Lissajous
  path around a home pose, slow clip open/close, periodic clutch presses).
* :class:`TrajectoryReplay` -- the same intention replayed from a CSV file (or from arrays
  extracted from a bag by the ROS adapter).
* :class:`HandDeviceModel` -- mass-damper model of hand + Touch device: the hand is a spring-damper
  pulling the device toward the intended position; the commanded force acts on the device mass.
* :class:`ConsoleCalibration` -- the real controller's calibration: position/orientation offsets
  per device and clip-range calibration (raw Simball clip reading -> angle).
* :class:`TouchballConsole` -- ties them together and produces protocol packets (protocol v2:
  authenticated, session handshake through :class:`saras_drivers.touchball_session.ConsoleSession`).

Units: metres, radians, seconds, kilograms, newtons. Frames: touch_<side>/base (z up, x away from
the user, y left).
"""

import csv
import math

from saras_drivers import touchball_protocol as tp
from saras_drivers.touchball_session import ConsoleSession


def quat_mul(a, b):
    """Hamilton product of quaternions (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def quat_from_rpy(roll, pitch, yaw):
    """Unit quaternion (x, y, z, w) of fixed-axis roll (x), pitch (y), yaw (z) [rad]."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def _nlerp(a, b, s):
    if sum(x * y for x, y in zip(a, b)) < 0.0:
        b = tuple(-x for x in b)
    q = tuple(x + s * (y - x) for x, y in zip(a, b))
    n = math.sqrt(sum(x * x for x in q))
    return tuple(x / n for x in q)


class Intention(object):
    """What the hand wants at one instant: position [m], orientation (x,y,z,w), raw clip [0..1],
    clutch and clip buttons."""
    __slots__ = ('position', 'orientation', 'clip_raw', 'clutch', 'clip_button')

    def __init__(self, position, orientation, clip_raw, clutch=False, clip_button=False):
        self.position = tuple(position)
        self.orientation = tuple(orientation)
        self.clip_raw = float(clip_raw)
        self.clutch = bool(clutch)
        self.clip_button = bool(clip_button)


class ScriptedMotion(object):
    """Scripted assistant-surgeon motion of one hand.

    Position: home + amplitude * (sin(2 pi f_x t), sin(2 pi f_y t + pi/2), sin(2 pi f_z t)) -- a
    Lissajous path; orientation: nominal rpy + small roll/pitch oscillation; raw clip reading
    0.5 + 0.5 sin(2 pi f_clip t); clutch pressed for ``clutch_duration`` every ``clutch_period``
    seconds (0 disables).

    Tissue contact (D7.2 Section 8 force path): every ``dip_period`` seconds from ``dip_start``,
    the hand leaves the path for ``dip_duration`` seconds and pushes down to the path's start
    point lowered by ``dip_depth`` [m] (master space; the slave goes ``scale_factor`` times as far:
    with the default 0.12 m and scale 0.5 the tools, ~5 cm above the tissue at the start, press a
    few mm into it), with smooth (raised-cosine) transitions over a quarter of the dip each, held
    in between. ``dip_period`` 0 disables. With ``servo`` (:class:`saras_simulation.dip_servo.DipServo`,
    fed with the tool tip the surgeon sees), the dip's depth and place follow the tool instead: the
    handle goes down until the tip is ``servo.depth`` into the tissue, towards ``servo.site``, and
    between dips the path is offset to keep the tip ``servo.hover`` above the tissue; a dip that
    begins before the servo sees the tool is skipped (a surgeon does not push blind). The surgeon
    then also moves along the path at ``pace`` (0-1) times its frequencies and stops on it during a
    dip (no blend towards ``home``): the pace a SARAS chain whose set-point may lead the arm by only
    a few mm follows on a loaded host (:mod:`saras_simulation.dip_servo`).
    """

    def __init__(self, home=(-0.10, 0.0, 0.08), amplitude=(0.02, 0.03, 0.015),
                 frequency=(0.2, 0.13, 0.17), rpy=(0.0, 0.0, 0.0), rpy_amplitude=0.15,
                 clip_frequency=0.25, clutch_period=0.0, clutch_duration=1.0, phase=0.0,
                 dip_depth=0.12, dip_period=20.0, dip_duration=9.0, dip_start=5.0, servo=None, pace=1.0):
        self.home = tuple(home)
        self.amplitude = tuple(amplitude)
        self.frequency = tuple(frequency)
        self.rpy = tuple(rpy)
        self.rpy_amplitude = float(rpy_amplitude)
        self.clip_frequency = float(clip_frequency)
        self.clutch_period = float(clutch_period)
        self.clutch_duration = float(clutch_duration)
        self.phase = float(phase)
        self.dip_depth, self.dip_period = float(dip_depth), float(dip_period)
        self.dip_duration, self.dip_start = float(dip_duration), float(dip_start)
        self.servo = servo
        if not (math.isfinite(pace) and 0.0 < pace <= 1.0):
            raise ValueError('pace must be in (0, 1], got %r' % (pace,))
        self.pace = float(pace)
        self._path = None                       # (console time, path time) [s]
        self._w = tuple(2.0 * math.pi * f for f in self.frequency)     # [rad/s]

    def __call__(self, t):
        b = self.dip_weight(t + self.phase)
        servo = self.servo.update(t, b) if self.servo is not None else None   # console time
        u = self._path_time(t, servo is not None, b) + self.phase
        t = t + self.phase
        w = self._w
        pos = (self.home[0] + self.amplitude[0] * math.sin(w[0] * u),
               self.home[1] + self.amplitude[1] * math.sin(w[1] * u + math.pi / 2),
               self.home[2] + self.amplitude[2] * math.sin(w[2] * u))
        if b > 0.0 and self.servo is None:     # open-loop dip; a servoed surgeon never dips blind
            target = (self.home[0], self.home[1] + self.amplitude[1], self.home[2] - self.dip_depth)
            pos = tuple((1.0 - b) * p + b * g for p, g in zip(pos, target))
        if servo is not None:                   # working height and dip (dip_servo), aim at the site
            pos = tuple(p + c for p, c in zip(pos, servo))
            self.servo.handle(pos)
        a = self.rpy_amplitude
        q = quat_from_rpy(self.rpy[0] + a * math.sin(w[1] * t), self.rpy[1] + a * math.sin(w[0] * t),
                          self.rpy[2])
        clip = 0.5 + 0.5 * math.sin(2.0 * math.pi * self.clip_frequency * t)
        clutch = (self.clutch_period > 0.0 and
                  (t % self.clutch_period) > self.clutch_period - self.clutch_duration)
        return Intention(pos, q, clip, clutch, clip > 0.9)

    def _path_time(self, t, servoed, b):
        """Time along the Lissajous path [s]: console time, or with a servo watching the tool
        ``pace`` times as fast and slowed to a stop during a dip (the surgeon presses, then goes on)."""
        if self._path is None or not servoed:
            self._path = (t, t)
        else:
            last_t, last_u = self._path
            self._path = (t, last_u + max(0.0, t - last_t) * self.pace * (1.0 - b))
        return self._path[1]

    def dip_weight(self, t):
        """Blend weight [0, 1] of the contact dip at script time ``t`` [s]."""
        if self.dip_period <= 0.0 or t < self.dip_start:
            return 0.0
        u = ((t - self.dip_start) % self.dip_period) / self.dip_duration
        if u >= 1.0:
            return 0.0
        ramp = min(u, 1.0 - u) * 4.0          # quarter up, half held, quarter down
        return 1.0 if ramp >= 1.0 else 0.5 - 0.5 * math.cos(math.pi * ramp)


CSV_FIELDS = ('x', 'y', 'z', 'qx', 'qy', 'qz', 'qw', 'clip', 'clutch', 'clip_button')


class TrajectoryReplay(object):
    """Replays a recorded intention of one device: linear interpolation of position and raw clip,
    normalised-lerp of the quaternion, buttons held from the previous sample. Loops if ``loop``.

    :param samples: list of (t [s], Intention), t strictly increasing.
    """

    def __init__(self, samples, loop=True):
        if len(samples) < 2:
            raise ValueError('a replay needs at least two samples')
        ts = [s[0] for s in samples]
        if any(b <= a for a, b in zip(ts, ts[1:])):
            raise ValueError('replay times must be strictly increasing')
        self.t0 = ts[0]
        self.times = [t - self.t0 for t in ts]
        self.samples = [s[1] for s in samples]
        self.loop = loop
        self._i = 0

    @property
    def duration(self):
        return self.times[-1]

    def __call__(self, t):
        if self.loop:
            t = t % self.duration
        t = min(max(t, 0.0), self.duration)
        i = self._i if self.times[self._i] <= t else 0
        while i + 1 < len(self.times) - 1 and self.times[i + 1] <= t:
            i += 1
        self._i = i
        a, b = self.samples[i], self.samples[i + 1]
        s = (t - self.times[i]) / (self.times[i + 1] - self.times[i])
        s = min(max(s, 0.0), 1.0)
        pos = tuple(x + s * (y - x) for x, y in zip(a.position, b.position))
        return Intention(pos, _nlerp(a.orientation, b.orientation, s),
                         a.clip_raw + s * (b.clip_raw - a.clip_raw), a.clutch, a.clip_button)

    @classmethod
    def from_states(cls, stamped_states, loop=True):
        """Build a replay from recorded ``saras_msgs/HapticDeviceState``-like objects.

        :param stamped_states: iterable of (t [s], msg) with msg.pose, msg.clip_angle, msg.clutch,
            msg.clip_button (duck-typed, so no ROS import here). Stale states and non-increasing
            times are skipped; the recorded clip angle is replayed as the raw clip reading.
        """
        samples = []
        for t, m in stamped_states:
            if getattr(m, 'stale', False) or (samples and t <= samples[-1][0]):
                continue
            p, q = m.pose.position, m.pose.orientation
            samples.append((t, Intention((p.x, p.y, p.z), (q.x, q.y, q.z, q.w), m.clip_angle,
                                         m.clutch, m.clip_button)))
        return cls(samples, loop)

    @classmethod
    def from_csv(cls, path, side, loop=True):
        """Load a CSV with header ``t`` and ``<side>_<field>`` for field in :data:`CSV_FIELDS`.

        Raises ValueError naming the file and the line on any malformed content.
        """
        samples = []
        with open(path, 'r') as f:
            reader = csv.DictReader(f)
            names = ['t'] + ['%s_%s' % (side, k) for k in CSV_FIELDS]
            missing = [n for n in names if n not in (reader.fieldnames or [])]
            if missing:
                raise ValueError('%s: missing columns %s' % (path, ', '.join(missing)))
            for row in reader:
                try:
                    v = [float(row[n]) for n in names]
                except (TypeError, ValueError):
                    raise ValueError('%s line %d: not a number' % (path, reader.line_num))
                if not all(math.isfinite(x) for x in v):
                    raise ValueError('%s line %d: non-finite value' % (path, reader.line_num))
                q = v[4:8]
                n = math.sqrt(sum(x * x for x in q))
                if n < 1e-6:
                    raise ValueError('%s line %d: zero quaternion' % (path, reader.line_num))
                samples.append((v[0], Intention(v[1:4], [x / n for x in q], v[8],
                                                v[9] > 0.5, v[10] > 0.5)))
        return cls(samples, loop)


class HandDeviceModel(object):
    """Translational mass-damper of the Touch device held by a compliant hand.

    m x'' = k_h (x_d - x) - b_h x' - b x' + f_cmd, integrated with semi-implicit Euler in
    sub-steps of at most ``max_step`` [s]. Orientation follows the intention (the Touch renders
    forces only). Default values: m = 0.25 kg (stylus + Simball + effective arm mass), hand
    stiffness 300 N/m and damping 8 N s/m, device damping 0.5 N s/m.
    """

    def __init__(self, mass=0.25, hand_stiffness=300.0, hand_damping=8.0, damping=0.5,
                 max_step=0.0005):
        for name, v in (('mass', mass), ('max_step', max_step)):
            if not v > 0.0:
                raise ValueError('%s must be > 0, got %r' % (name, v))
        for name, v in (('hand_stiffness', hand_stiffness), ('hand_damping', hand_damping),
                        ('damping', damping)):
            if not v >= 0.0:
                raise ValueError('%s must be >= 0, got %r' % (name, v))
        self.m, self.k, self.bh, self.b = float(mass), float(hand_stiffness), float(hand_damping), float(damping)
        self.max_step = float(max_step)
        self.x = None
        self.v = [0.0, 0.0, 0.0]

    def reset(self, position):
        self.x = list(position)
        self.v = [0.0, 0.0, 0.0]

    def step(self, dt, target, force):
        """Advance by dt [s] toward ``target`` [m] under ``force`` [N]; returns the position."""
        if self.x is None:
            self.reset(target)
        n = max(1, int(math.ceil(dt / self.max_step)))
        h = dt / n
        k, c, m = self.k, self.bh + self.b, self.m
        x, v = self.x, self.v
        for i in range(3):                      # semi-implicit Euler, axes are independent
            xi, vi, ti, fi = x[i], v[i], target[i], force[i]
            for _ in range(n):
                vi += h * ((k * (ti - xi) - c * vi + fi) / m)
                xi += h * vi
            x[i], v[i] = xi, vi
        return tuple(x)


class ConsoleCalibration(object):
    """Calibration offered by the Touchball controller for one device.

    * position offset [m] and orientation offset (quaternion, applied on the left) so that the
      device reads a chosen reference pose (``calibrate_pose``);
    * clip-range calibration: the raw Simball clip reading is mapped linearly from
      [raw_closed, raw_open] to [0, clip_max] rad and clipped (``calibrate_clip``).
    """

    def __init__(self, position_offset=(0.0, 0.0, 0.0), orientation_offset=(0.0, 0.0, 0.0, 1.0),
                 raw_closed=0.0, raw_open=1.0, clip_max=1.0):
        self.position_offset = tuple(position_offset)
        self.orientation_offset = tuple(orientation_offset)
        self.set_clip_range(raw_closed, raw_open, clip_max)

    def set_clip_range(self, raw_closed, raw_open, clip_max):
        if not math.isfinite(raw_closed) or not math.isfinite(raw_open) or raw_open == raw_closed:
            raise ValueError('clip range needs two distinct finite raw readings')
        if not clip_max > 0.0:
            raise ValueError('clip_max must be > 0 rad')
        self.raw_closed, self.raw_open, self.clip_max = float(raw_closed), float(raw_open), float(clip_max)

    def calibrate_clip(self, raw_readings_closed, raw_readings_open):
        """Clip-range calibration from readings with the clip held closed, then fully open."""
        self.set_clip_range(sum(raw_readings_closed) / len(raw_readings_closed),
                            sum(raw_readings_open) / len(raw_readings_open), self.clip_max)

    def calibrate_pose(self, raw_position, raw_orientation, reference_position,
                       reference_orientation=(0.0, 0.0, 0.0, 1.0)):
        """Choose offsets so that the current raw pose reads as the reference pose."""
        inv = (-raw_orientation[0], -raw_orientation[1], -raw_orientation[2], raw_orientation[3])
        self.orientation_offset = quat_mul(reference_orientation, inv)
        self.position_offset = tuple(r - p for r, p in zip(reference_position, raw_position))

    def clip_angle(self, raw):
        s = (raw - self.raw_closed) / (self.raw_open - self.raw_closed)
        return self.clip_max * min(max(s, 0.0), 1.0)

    def apply(self, position, orientation):
        p = tuple(a + b for a, b in zip(position, self.position_offset))
        return p, quat_mul(self.orientation_offset, orientation)


class TouchballConsole(object):
    """The simulated controller: intentions -> device models -> calibrated, authenticated packets.

    :param sources: (left, right) callables t -> :class:`Intention`.
    :param mac: :class:`touchball_protocol.Mac` of the deployment key.
    :param command_timeout: a force command older than this [s] is dropped (zero force).
    :param rebind_after: no valid command for this long [s] => new handshake (ConsoleSession).
    """

    def __init__(self, sources, mac, models=None, calibrations=None, command_timeout=0.1, rebind_after=1.0):
        self.sources = tuple(sources)
        self.models = tuple(models) if models else (HandDeviceModel(), HandDeviceModel())
        self.calibrations = tuple(calibrations) if calibrations else (ConsoleCalibration(),
                                                                      ConsoleCalibration())
        self.command_timeout = float(command_timeout)
        self.session = ConsoleSession(mac, rebind_after=rebind_after)
        self.t = 0.0

    @property
    def commands_received(self):
        return self.session.commands_received

    @property
    def commands_rejected(self):
        return self.session.commands_rejected

    def handle_command(self, data, now):
        """Handle a datagram of the ROS side (challenge or command; any defect => counted, ignored).
        True if it was valid."""
        return self.session.handle(data, now) is not None

    def active_forces(self, now):
        t = self.session.command_time
        if t is None or now - t > self.command_timeout or not self.session.bound:
            return ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        return tuple(c.force if c.enabled else (0.0, 0.0, 0.0) for c in self.session.commands)

    def step(self, dt, now=None):
        """Advance the simulation by dt [s]; returns the (left, right) DeviceState."""
        self.t += dt
        now = self.t if now is None else now
        forces = self.active_forces(now)
        states = []
        for src, model, cal, f in zip(self.sources, self.models, self.calibrations, forces):
            it = src(self.t)
            x = model.step(dt, it.position, f)
            p, q = cal.apply(x, it.orientation)
            states.append(tp.DeviceState(p, q, cal.clip_angle(it.clip_raw), it.clutch, it.clip_button))
        return tuple(states)

    def packet(self, devices, sender_time, now=None):
        """The next datagram: a state packet once a session is bound, else a hello when one is due
        (None in between). ``now``: monotonic time [s] (default: the simulation time)."""
        return self.session.outgoing(devices, sender_time, self.t if now is None else now)
