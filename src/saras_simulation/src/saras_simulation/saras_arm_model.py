"""Endoscope Robot + SARAS Adapter model (ROS-agnostic), used by ``saras_arm_sim``.

Six motors: the Endoscope Robot's yaw, pitch (pivoting about the RCM), insertion and roll, and the
SARAS Adapter's instrument roll and jaw. The passive Positioning Arm is fixed during operation (its
setup pose places the RCM). Joint motion is velocity-limited and synchronised: every step, the five
positioning joints advance toward their target along a straight line in joint space at the largest
speed for which no motor exceeds its limit (revolute motors: ``max_velocity`` [rad/s]; insertion:
``max_velocity * insertion_ratio`` [m/s]), and (``max_tip_speed``) no faster than that [m/s] at the
tool tip, as the controller's Cartesian speed limit: a target far from the arm (after a stall of
its commander, a late set-point) is approached at that speed, never at the motors' full speed.
The jaw moves on its own toward its target at
``jaw_velocity`` [rad/s] (opening the clip neither slows nor waits for the arm's motion).
Integration sub-steps are at most ``1 / min_rate`` seconds (default 500 Hz).

Targets are validated before anything changes: a rejected target causes no motion.
"""

import math

import numpy as np

from saras_drivers import saras_arm_protocol as proto

IDX_INSERTION = 2
IDX_ER_ROLL = 3
IDX_ADAPTER_ROLL = 4
IDX_JAW = 5


def quat_to_matrix(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def matrix_to_quat(r):
    """Unit quaternion (x, y, z, w), w >= 0, of a rotation matrix (Shepperd's method)."""
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    if tr > 0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = (0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s)
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = ((r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = ((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s)
    q = np.array(q)
    q /= np.linalg.norm(q)
    return tuple(-q if q[3] < 0 else q)


class TargetRejected(proto.ProtocolError):
    pass


class SarasArmModel(object):
    """State and motion of one SARAS arm.

    :param kin: an ``saras_arm_kinematics`` object (rcm_in_base, tip_in_rcm, ik_tip, lower, upper).
    :param max_velocity: initial motor velocity limit [rad/s].
    :param max_velocity_limit: hardware limit: set_max_velocity above it is rejected [rad/s].
    :param insertion_ratio: insertion speed per unit motor speed [m/rad].
    :param rcm_axis_tolerance: max angle [rad] between a target orientation's shaft axis and the
        RCM->tip line; larger => ``rcm_violation``.
    :param position_tolerance: FK(IK(target)) must reproduce the target to this [m].
    :param min_rate: minimum internal integration rate [Hz].
    :param min_depth: the tip must be at least this far [m] inside the trocar (along the
        neutral shaft axis); closer or outside => ``rcm_violation``.
    :param jaw_velocity: jaw speed limit [rad/s] (independent of ``max_velocity``).
    :param max_tip_speed: tool-tip speed limit [m/s] (None: only the motor limits).
    """

    def __init__(self, kin, max_velocity=1.0, max_velocity_limit=3.0, insertion_ratio=0.05,
                 rcm_axis_tolerance=math.pi / 2, position_tolerance=1e-6, min_rate=500.0,
                 min_depth=0.01, initial_joints=None, jaw_velocity=2.0, max_tip_speed=None):
        if not 0.0 < max_velocity <= max_velocity_limit:
            raise ValueError('max_velocity must be in (0, max_velocity_limit], got %r' % max_velocity)
        if not insertion_ratio > 0.0:
            raise ValueError('insertion_ratio must be > 0 m/rad')
        if not (math.isfinite(jaw_velocity) and jaw_velocity > 0.0):
            raise ValueError('jaw_velocity must be > 0 rad/s')
        self.jaw_velocity = float(jaw_velocity)
        if max_tip_speed is not None and not (math.isfinite(max_tip_speed) and max_tip_speed > 0.0):
            raise ValueError('max_tip_speed must be > 0 m/s (or None), got %r' % (max_tip_speed,))
        self.max_tip_speed = None if max_tip_speed is None else float(max_tip_speed)
        self._tip_cache = (None, None)     # (joints, tip position in the RCM frame)
        if not min_rate >= 500.0:
            raise ValueError('min_rate must be >= 500 Hz')
        self.kin = kin
        self.lower = np.asarray(kin.lower, dtype=float)
        self.upper = np.asarray(kin.upper, dtype=float)
        self.max_velocity_limit = float(max_velocity_limit)
        self.insertion_ratio = float(insertion_ratio)
        self.rcm_axis_tolerance = float(rcm_axis_tolerance)
        self.position_tolerance = float(position_tolerance)
        self.max_step = 1.0 / float(min_rate)
        if not min_depth >= 0.0:
            raise ValueError('min_depth must be >= 0 m')
        self.min_depth = float(min_depth)
        self.max_velocity = float(max_velocity)
        self._rcm = np.asarray(kin.rcm_in_base(), dtype=float)
        self._rcm_inv = np.linalg.inv(self._rcm)
        if initial_joints is None:
            initial_joints = 0.5 * (self.lower + self.upper)
            initial_joints[IDX_INSERTION] = self.lower[IDX_INSERTION] + 0.5 * (
                self.upper[IDX_INSERTION] - self.lower[IDX_INSERTION])
        self.q = np.clip(np.asarray(initial_joints, dtype=float), self.lower, self.upper)
        self.target = self.q.copy()
        self.target_id = 0
        self.time = 0.0
        self._speed = np.empty(6)
        self._update_speed()
        # inward shaft direction in the RCM frame at zero pivot angles
        qz = self.q.copy()
        qz[:2] = 0.0
        qz[IDX_INSERTION] = 1.0
        self._inward = self.kin.tip_in_rcm(qz)[:3, 3]
        self._inward = self._inward / np.linalg.norm(self._inward)

    # ------------------------------------------------------------------ commands
    def _update_speed(self):
        self._speed[:] = self.max_velocity
        self._speed[IDX_INSERTION] = self.max_velocity * self.insertion_ratio
        self._speed[IDX_JAW] = self.jaw_velocity

    def set_max_velocity(self, v):
        if not (math.isfinite(v) and 0.0 < v <= self.max_velocity_limit):
            raise TargetRejected(proto.BAD_VALUE, 'max_velocity must be in (0, %g] rad/s, got %r'
                                 % (self.max_velocity_limit, v))
        self.max_velocity = float(v)
        self._update_speed()

    def solve(self, position, orientation=None):
        """Joint target for a tip pose in the base frame; raises :class:`TargetRejected`."""
        p = self._rcm_inv[:3, :3].dot(np.asarray(position, dtype=float)) + self._rcm_inv[:3, 3]
        if not np.all(np.isfinite(p)):
            raise TargetRejected(proto.BAD_PAYLOAD, 'non-finite target')
        depth = float(p.dot(self._inward))
        if depth < self.min_depth or depth <= 0.0:
            raise TargetRejected(proto.RCM_VIOLATION,
                                 'target is %.1f mm inside the trocar, the minimum is %.1f mm'
                                 % (1e3 * depth, 1e3 * self.min_depth))
        q = self.target.copy()
        try:
            er = self.kin.ik_tip(p, 0.0)
        except ValueError as e:
            raise TargetRejected(proto.RCM_VIOLATION, str(e))
        q[:4] = er[:4]
        q[IDX_ER_ROLL] = self.target[IDX_ER_ROLL]
        t = self.kin.tip_in_rcm(q)
        if np.linalg.norm(t[:3, 3] - p) > self.position_tolerance:
            raise TargetRejected(proto.RCM_VIOLATION, 'target not reachable through the RCM')
        if orientation is not None:
            r_des = self._rcm_inv[:3, :3].dot(quat_to_matrix(orientation))
            shaft = t[:3, :3][:, 2]
            cosang = float(np.clip(r_des[:, 2].dot(shaft), -1.0, 1.0))
            if math.acos(cosang) > self.rcm_axis_tolerance:
                raise TargetRejected(proto.RCM_VIOLATION,
                                     'orientation axis %.1f deg off the RCM line' % math.degrees(math.acos(cosang)))
            # swing-twist: roll about the shaft that best matches the desired x axis
            x_cur = t[:3, :3][:, 0]
            y_cur = t[:3, :3][:, 1]
            x_des = r_des[:, 0] - r_des[:, 0].dot(shaft) * shaft
            droll = math.atan2(x_des.dot(y_cur), x_des.dot(x_cur))
            q[IDX_ER_ROLL] = math.atan2(math.sin(q[IDX_ER_ROLL] + droll), math.cos(q[IDX_ER_ROLL] + droll))
        bad = [i for i in range(4) if not self.lower[i] - 1e-12 <= q[i] <= self.upper[i] + 1e-12]
        if bad:
            names = ', '.join('%s=%.4g' % (proto.MOTOR_JOINTS[i], q[i]) for i in bad)
            raise TargetRejected(proto.WORKSPACE, 'outside joint limits: %s' % names)
        return q

    def set_target(self, position, orientation=None, cmd_id=0):
        """Validate and accept a tip target (base frame). No state change if rejected."""
        q = self.solve(position, orientation)
        self.target = q
        self.target_id = int(cmd_id)

    def set_clip(self, jaw=None, roll=None):
        q = self.target.copy()
        if jaw is not None:
            q[IDX_JAW] = jaw
        if roll is not None:
            q[IDX_ADAPTER_ROLL] = roll
        for i in (IDX_JAW, IDX_ADAPTER_ROLL):
            if not self.lower[i] <= q[i] <= self.upper[i]:
                raise TargetRejected(proto.WORKSPACE, '%s=%.4g outside [%g, %g]'
                                     % (proto.MOTOR_JOINTS[i], q[i], self.lower[i], self.upper[i]))
        self.target[IDX_JAW] = q[IDX_JAW]
        self.target[IDX_ADAPTER_ROLL] = q[IDX_ADAPTER_ROLL]

    def hold(self):
        """Stop where the arm is: the target becomes the current joint vector."""
        self.target = self.q.copy()

    # ------------------------------------------------------------------ motion
    def step(self, dt):
        """Advance by dt [s] in sub-steps of at most 1/min_rate. Returns True while moving."""
        if not dt > 0.0:
            return self.moving
        self.time += dt
        if not self.moving:            # at the target: nothing to integrate (idle fast path)
            return False
        jaw_err = self.target[IDX_JAW] - self.q[IDX_JAW]
        jaw_step = self.jaw_velocity * dt
        self.q[IDX_JAW] = self.target[IDX_JAW] if abs(jaw_err) <= jaw_step else \
            self.q[IDX_JAW] + math.copysign(jaw_step, jaw_err)
        n = max(1, int(math.ceil(dt / self.max_step - 1e-9)))
        h = dt / n
        # plain floats: numpy's per-call overhead on 6-vectors was most of this loop's cost (the
        # simulator calls it for every state sample and command); same operations, same rounding.
        # The synchronised group: every joint but the jaw.
        q, target, speed = (v.tolist()[:IDX_JAW] for v in (self.q, self.target, self._speed))
        for _ in range(n):
            err = [t - x for t, x in zip(target, q)]
            scale = max(abs(e) / (v * h) for e, v in zip(err, speed))
            if scale <= 1.0:
                q = target
                break                  # reached: the remaining sub-steps would not move
            q = [x + e / scale for x, e in zip(q, err)]
        if self.max_tip_speed is not None:
            q = self._limit_tip_speed(q, self.max_tip_speed * dt)
        self.q[:IDX_JAW] = q
        return self.moving

    def _tip(self, q5):
        """Tip position in the RCM frame for the first five joints (cached for the last one)."""
        key = tuple(q5)
        if self._tip_cache[0] != key:
            full = self.q.copy()
            full[:IDX_JAW] = q5
            self._tip_cache = (key, self.kin.tip_in_rcm(full)[:3, 3])
        return self._tip_cache[1]

    def _limit_tip_speed(self, q, reach):
        """Shorten the step from the current joints to q (a straight line in joint space) so that the
        tip moves at most reach [m]; a few secant iterations on the chord."""
        q0 = self.q.tolist()[:IDX_JAW]
        p0 = self._tip(q0)
        frac = 1.0
        for _ in range(4):
            qf = [a + frac * (b - a) for a, b in zip(q0, q)]
            d = float(np.linalg.norm(self._tip(qf) - p0))
            if d <= reach * (1.0 + 1e-9):
                return qf
            frac *= reach / d
        return [a + frac * (b - a) for a, b in zip(q0, q)]

    @property
    def moving(self):
        return self.q.tolist() != self.target.tolist()

    # ------------------------------------------------------------------ state
    def tip_in_base(self, q=None):
        return self._rcm.dot(self.kin.tip_in_rcm(self.q if q is None else q))

    def rcm_position(self):
        return self._rcm[:3, 3].copy()

    def joint_velocity_limits(self):
        return self._speed.copy()
