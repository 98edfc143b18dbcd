"""Scripted main-surgeon motion for the simulated da Vinci (dVRK 1.x topics), ROS-agnostic.

Contents
--------
* :func:`load_kinematics`: the dVRK PSM and ECM kinematics in each arm's base frame (= its remote
  centre of motion, RCM; tool tip at negative z when inserted, dVRK convention), an adapter over
  ``saras_description.kinematics`` (the URDF-consistent model robot_state_publisher uses), so that
  the published cartesian poses and joint states agree with the URDF.
* :class:`SuturingMotion`: a periodic suturing-like pattern for one PSM (needle drive along a
  vertical arc into the tissue, pull, return, next stitch along the wound).
* :class:`EcmMotion`: the endoscope holder dwells, then now and then moves smoothly to the next
  viewpoint.
* :class:`ReplaySchedule`: time-ordered replay of recorded samples (bag replay) with loop support.

Units: metres, radians, seconds. Transforms are 4x4 numpy arrays (see :mod:`saras_common.transforms`).
"""
import bisect
import math

import numpy as np

from saras_common import transforms as tfm

#: Joint names published on /dvrk/PSM*/state_joint_current (dVRK 1.x).
PSM_JOINT_NAMES = ('outer_yaw', 'outer_pitch', 'outer_insertion', 'outer_roll',
                   'outer_wrist_pitch', 'outer_wrist_yaw')
#: Joint names published on /dvrk/ECM/state_joint_current (dVRK 1.x).
ECM_JOINT_NAMES = ('outer_yaw', 'outer_pitch', 'insertion', 'outer_roll')


def smoothstep(x):
    """C1 ramp 0 -> 1 on [0, 1] (3x^2 - 2x^3), clamped outside."""
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def shaft_rotation(yaw, pitch):
    """Orientation of the instrument shaft in the arm base frame.

    The z axis of the returned frame points along the shaft away from the RCM (into the
    patient); at ``yaw = pitch = 0`` it is the base's -z (dVRK convention). ``yaw`` rotates
    about -y, ``pitch`` about -x (as saras_description.kinematics.pivot_tip): the shaft direction
    is ``(sin(yaw) cos(pitch), -sin(pitch), -cos(yaw) cos(pitch))``.
    """
    return (tfm.rot_y(-yaw) @ tfm.rot_x(-pitch) @ tfm.rot_x(math.pi))[:3, :3]


def shaft_direction(yaw, pitch):
    """Unit vector from the RCM along the shaft (base frame)."""
    return shaft_rotation(yaw, pitch)[:, 2]


def direction_to_yaw_pitch(d):
    """Inverse of :func:`shaft_direction` (``d`` need not be unit). Returns (yaw, pitch) [rad]."""
    d = np.asarray(d, dtype=float)
    r = np.linalg.norm(d)
    if not r > 1e-9:
        raise ValueError('direction has zero length')
    d = d / r
    pitch = math.asin(max(-1.0, min(1.0, -d[1])))
    yaw = math.atan2(d[0], -d[2])
    return yaw, pitch


class DescriptionKinematics(object):
    """Adapter over ``saras_description.kinematics`` (URDF-consistent model): ``outer_insertion`` is
    the tip depth with the wrist straight; the optical frames come from the hand-eye calibration
    (``saras_description/config/ecm_hand_eye.yaml``), exactly as robot_state_publisher broadcasts them.
    """
    name = 'saras_description'

    def __init__(self, module, hand_eye):
        self._m = module
        self._hand_eye = hand_eye

    def psm_tip_in_base(self, q):
        """4x4 pose of the PSM tool tip in the PSM base (RCM) frame for 6 joint values."""
        return np.asarray(self._m.psm_tip_in_base(list(q)), dtype=float)

    def psm_ik_position(self, wrist_point):
        """(yaw, pitch, insertion) placing the wrist pivot at ``wrist_point`` (base frame, m)."""
        return tuple(float(v) for v in self._m.psm_ik_position(np.asarray(wrist_point))[:3])

    def ecm_tip_in_base(self, q):
        """4x4 pose of the ECM camera tip in the ECM base (RCM) frame for 4 joint values."""
        return np.asarray(self._m.ecm_tip_in_base(list(q)), dtype=float)

    def camera_in_tip(self, eye):
        """4x4 pose of ``endoscope/<eye>_optical_frame`` in ``ECM/tool_tip`` (hand-eye)."""
        left = np.asarray(self._hand_eye.tip_to_left, dtype=float)
        return left if eye == 'left' else left @ np.asarray(self._hand_eye.left_to_right, dtype=float)


def load_kinematics():
    """Kinematics used by the simulator: saras_description's model and hand-eye calibration."""
    from saras_description import config as desc_config
    from saras_description import kinematics as mod
    return DescriptionKinematics(mod, desc_config.load_hand_eye())


class SuturingMotion(object):
    """Periodic suturing-like motion of one PSM, expressed as wrist-pivot targets in the base frame.

    One stitch lasts ``period`` seconds: needle drive (half a turn of an arc of radius
    ``arc_radius`` in the vertical plane spanned by ``drive_dir`` and base z, dipping down),
    pull (lift by ``lift``), return to the start. Successive stitches advance along ``wound_dir``
    by ``stitch_spacing`` and wrap after ``stitches`` stitches.
    """

    def __init__(self, centre, drive_dir=(1.0, 0.0, 0.0), wound_dir=(0.0, 1.0, 0.0),
                 arc_radius=0.012, lift=0.025, period=8.0, stitches=4, stitch_spacing=0.006,
                 phase=0.0):
        self.centre = np.asarray(centre, dtype=float)
        u = np.asarray(drive_dir, dtype=float)
        self.u = u / np.linalg.norm(u)
        v = np.asarray(wound_dir, dtype=float)
        self.v = v / np.linalg.norm(v)
        self.w = np.array([0.0, 0.0, 1.0])
        self.arc_radius = float(arc_radius)
        self.lift = float(lift)
        self.period = float(period)
        self.stitches = int(stitches)
        self.spacing = float(stitch_spacing)
        self.phase = float(phase)
        if not (self.period > 0 and self.arc_radius > 0 and self.stitches >= 1):
            raise ValueError('SuturingMotion: period, arc_radius must be > 0, stitches >= 1')

    def stitch_centre(self, k):
        """Centre of stitch ``k``: back and forth along the wound (0, 1, .., n-1, n-2, .., 1, 0, ..)."""
        n = self.stitches
        i = 0 if n == 1 else k % (2 * n - 2)
        if i >= n:
            i = 2 * n - 2 - i
        return self.centre + (i - (n - 1) / 2.0) * self.spacing * self.v

    def wrist_point(self, t):
        """Wrist pivot position [m] (base frame) and needle angle [rad] at time ``t`` [s].

        Continuous in time: the move to the next stitch happens during the return phase.
        """
        cyc = t / self.period + self.phase
        k = int(math.floor(cyc))
        s = cyc - k
        c = self.stitch_centre(k)
        r, u, w = self.arc_radius, self.u, self.w
        if s < 0.5:
            phi = math.pi * smoothstep(s / 0.5)
            p = c + r * (math.cos(phi) * u - math.sin(phi) * w)
        elif s < 0.75:
            phi = math.pi
            p = c - r * u + smoothstep((s - 0.5) / 0.25) * self.lift * w
        else:
            b = smoothstep((s - 0.75) / 0.25)
            phi = math.pi * (1.0 - b)
            start = c - r * u + self.lift * w
            end = self.stitch_centre(k + 1) + r * u
            p = start + b * (end - start)
        return p, phi

    def joints(self, t, kin):
        """Six PSM joint values at time ``t`` using ``kin.psm_ik_position`` for the shaft."""
        p, phi = self.wrist_point(t)
        yaw, pitch, ins = kin.psm_ik_position(p)
        s = 2.0 * math.pi * (t / self.period + self.phase)
        return [yaw, pitch, ins, phi - math.pi / 2.0, 0.3 * math.sin(s), 0.2 * math.sin(2.0 * s)]


class EcmMotion(object):
    """ECM dwelling at a viewpoint, moving now and then (smooth joint-space blend) to the next.

    ``viewpoints``: list of dicts ``{look_at: [x, y, z] (base frame, m), insertion: m,
    roll: rad}``. Cycle per viewpoint: ``dwell`` seconds still, then ``move_time`` seconds of motion.
    """

    def __init__(self, viewpoints, dwell=20.0, move_time=3.0):
        if not viewpoints:
            raise ValueError('EcmMotion: at least one viewpoint is required')
        self.poses = []
        for vp in viewpoints:
            yaw, pitch = direction_to_yaw_pitch(vp['look_at'])
            ins = float(vp.get('insertion', 0.08))
            if not 0.0 < ins < 0.3:
                raise ValueError('EcmMotion: insertion %.3f m out of (0, 0.3)' % ins)
            self.poses.append(np.array([yaw, pitch, ins, float(vp.get('roll', 0.0))]))
        self.dwell = float(dwell)
        self.move_time = float(move_time)
        if self.dwell < 0 or self.move_time <= 0:
            raise ValueError('EcmMotion: dwell must be >= 0 and move_time > 0')

    def joints(self, t):
        """Four ECM joint values at time ``t`` [s]."""
        n = len(self.poses)
        if n == 1:
            return list(self.poses[0])
        seg = self.dwell + self.move_time
        k = int(math.floor(t / seg))
        s = t - k * seg
        a, b = self.poses[k % n], self.poses[(k + 1) % n]
        if s < self.dwell:
            return list(a)
        return list(a + smoothstep((s - self.dwell) / self.move_time) * (b - a))


class DvrkSimCore(object):
    """All three arms: joint values and tip poses at time ``t`` (ROS-agnostic core of dvrk_sim)."""

    def __init__(self, kinematics, psm_motions, ecm_motion):
        self.kin = kinematics
        self.psm_motions = dict(psm_motions)
        self.ecm_motion = ecm_motion

    def sample(self, t):
        """``{arm: (joint_values list, T_base_tip 4x4)}`` for PSMs and ``ECM`` at time ``t`` [s]."""
        out = {}
        for arm, m in self.psm_motions.items():
            q = m.joints(t, self.kin)
            out[arm] = (q, self.kin.psm_tip_in_base(q))
        if self.ecm_motion is not None:
            q = self.ecm_motion.joints(t)
            out['ECM'] = (q, self.kin.ecm_tip_in_base(q))
        return out

    @classmethod
    def from_config(cls, cfg, kinematics=None):
        """Build from the ``dvrk_sim.yaml`` dictionary; raises ValueError naming the bad key."""
        kin = kinematics or load_kinematics()
        psms = {}
        for arm, p in (cfg.get('psm') or {}).items():
            try:
                psms[arm] = SuturingMotion(
                    centre=_vec3(p['centre'], 'psm/%s/centre' % arm),
                    drive_dir=_vec3(p.get('drive_dir', [1, 0, 0]), 'psm/%s/drive_dir' % arm),
                    wound_dir=_vec3(p.get('wound_dir', [0, 1, 0]), 'psm/%s/wound_dir' % arm),
                    arc_radius=p.get('arc_radius', 0.012), lift=p.get('lift', 0.025),
                    period=p.get('period', 8.0), stitches=p.get('stitches', 4),
                    stitch_spacing=p.get('stitch_spacing', 0.006), phase=p.get('phase', 0.0))
            except (KeyError, TypeError, ValueError) as ex:
                raise ValueError('parameter psm/%s invalid: %s' % (arm, ex))
        ecm = None
        if cfg.get('ecm'):
            e = cfg['ecm']
            try:
                ecm = EcmMotion(e['viewpoints'], e.get('dwell', 20.0), e.get('move_time', 3.0))
            except (KeyError, TypeError, ValueError) as ex:
                raise ValueError('parameter ecm invalid: %s' % ex)
        return cls(kin, psms, ecm)


def _vec3(v, name):
    try:
        a = np.asarray([float(x) for x in v])
    except (TypeError, ValueError):
        raise ValueError('%s must be 3 numbers' % name)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError('%s must be 3 finite numbers' % name)
    return a


class ReplaySchedule(object):
    """Replays time-stamped records ``(t [s], key, payload)`` relative to a start time.

    ``due(elapsed)`` returns, in order, the records whose relative time lies in the window since
    the previous call; with ``loop`` the recording restarts after its last record (+ one median
    sample interval, so the loop boundary keeps the recorded rate).
    """

    def __init__(self, records, loop=False):
        recs = sorted(records, key=lambda r: r[0])
        if not recs:
            raise ValueError('ReplaySchedule: no records')
        t0 = recs[0][0]
        self.times = [r[0] - t0 for r in recs]
        self.records = recs
        self.loop = bool(loop)
        gaps = np.diff(self.times)
        gaps = gaps[gaps > 0]
        self.duration = self.times[-1] + (float(np.median(gaps)) if len(gaps) else 0.01)
        self._next = 0
        self._base = 0.0

    @property
    def finished(self):
        return not self.loop and self._next >= len(self.records)

    def due(self, elapsed):
        out = []
        while True:
            rel = elapsed - self._base
            j = bisect.bisect_right(self.times, rel)
            if j > self._next:
                out.extend(self.records[self._next:j])
                self._next = j
            if self.loop and self._next >= len(self.records) and rel >= self.duration:
                self._base += self.duration
                self._next = 0
                continue
            return out


class SampleGrid(object):
    """Sample instants on a fixed grid of ``period`` [s], as a real-time publisher thread keeps
    them: :meth:`due` returns the grid times up to ``now`` not yet returned, at most
    ``max_catch_up`` (a late wake-up is made good at once, with the samples' own times); when
    further behind, or when the clock jumped back, the grid restarts at ``now`` and the skipped
    samples are counted in ``missed``."""

    def __init__(self, period, max_catch_up=10):
        if not (period > 0 and math.isfinite(period)):
            raise ValueError('sample period must be > 0 s, got %r' % (period,))
        if isinstance(max_catch_up, bool) or not isinstance(max_catch_up, int) or max_catch_up < 1:
            raise ValueError('max_catch_up must be an integer >= 1, got %r' % (max_catch_up,))
        self.period = float(period)
        self.max_catch_up = max_catch_up
        self.k0 = None       # grid origin [s]
        self.k = 0           # index of the next sample
        self.missed = 0

    def due(self, now):
        """Grid times [s] <= ``now`` [s] not returned before (list, oldest first)."""
        if self.k0 is None or now < self.k0 + (self.k - 1) * self.period:
            self.k0, self.k = now, 0            # start, or the clock jumped back
        out = []
        while len(out) < self.max_catch_up:
            t = self.k0 + self.k * self.period
            if t > now + 1e-9:
                return out
            out.append(t)
            self.k += 1
        behind = int(math.floor((now - (self.k0 + self.k * self.period)) / self.period + 1e-9)) + 1
        if behind > 0:                          # still behind: skip to now
            self.missed += behind
            self.k0, self.k = now + self.period, 0
        return out
