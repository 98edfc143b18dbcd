"""CRTK (dVRK 2.x) behaviour of one simulated arm, ROS-agnostic.

* :class:`OperatingState`: the CRTK state machine (``state_command`` enable / disable / home /
  unhome / pause / resume -> ``operating_state`` DISABLED / ENABLED / PAUSED, ``is_homed``,
  ``is_busy``).
* :class:`JointMove`: an interpolated joint move (quintic time scaling, duration from the joint
  velocity and acceleration limits), as the dVRK's ``move_jp``/``move_cp`` trajectory generator.
* :class:`CrtkArm`: one arm: who drives it (the scripted surgeon or a client), ``servo_jp``,
  ``servo_cp``, ``move_jp``, ``move_cp`` and, for a PSM, its jaw; :meth:`CrtkArm.step` gives the
  joint values of every tick.

Arbitration: the arm follows its script (``scripted``) until a client sends a command (a motion
command or ``state_command``); it then holds or moves as commanded (``client``). When no client
command arrived for ``client_timeout`` seconds and no move runs, the arm blends back to the script
over ``rejoin_time`` seconds (``rejoin``: no jump) and follows it again. A disabled arm holds and
ignores motion commands (as the dVRK) until enabled; it does not time out. Motion commands are
accepted when ENABLED and homed (the dVRK's ready state).

Units: metres, radians, seconds.
"""
import math

import numpy as np

SCRIPTED, CLIENT, REJOIN = 'scripted', 'client', 'rejoin'
STATE_COMMANDS = ('enable', 'disable', 'home', 'unhome', 'pause', 'resume')


class OperatingState(object):
    """CRTK operating state. The simulated console starts powered and homed (ENABLED, homed)."""

    def __init__(self, state='ENABLED', homed=True):
        self.state = state
        self.homed = bool(homed)

    def command(self, cmd):
        """Apply a CRTK state command; raises ValueError for an unknown one."""
        if cmd not in STATE_COMMANDS:
            raise ValueError('unknown state command %r (expected one of %s)'
                             % (cmd, ', '.join(STATE_COMMANDS)))
        if cmd in ('enable', 'home'):
            # home powers the arm too (dVRK: "home" enables then homes)
            if self.state != 'PAUSED' or cmd == 'home':
                self.state = 'ENABLED'
            if cmd == 'home':
                self.homed = True
        elif cmd == 'disable':
            self.state = 'DISABLED'
        elif cmd == 'unhome':
            self.homed = False
        elif cmd == 'pause' and self.state == 'ENABLED':
            self.state = 'PAUSED'
        elif cmd == 'resume' and self.state == 'PAUSED':
            self.state = 'ENABLED'

    @property
    def ready(self):
        return self.state == 'ENABLED' and self.homed


def quintic(s):
    """Minimum-jerk time scaling 0 -> 1 on [0, 1] (zero velocity and acceleration at both ends)."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)


class JointMove(object):
    """Interpolated move from ``start`` to ``goal`` beginning at ``t0`` [s]. The duration is the
    shortest one keeping every joint within ``v_max`` [unit/s] and ``a_max`` [unit/s^2] (quintic
    peak velocity 1.875 d/T, peak acceleration 5.774 d/T^2)."""

    def __init__(self, start, goal, t0, v_max, a_max):
        self.start = np.asarray(start, dtype=float)
        self.goal = np.asarray(goal, dtype=float)
        self.t0 = float(t0)
        d = np.abs(self.goal - self.start)
        v = np.broadcast_to(np.asarray(v_max, dtype=float), d.shape)
        a = np.broadcast_to(np.asarray(a_max, dtype=float), d.shape)
        t = np.maximum(1.875 * d / v, np.sqrt(5.774 * d / a)) if d.size else np.zeros(0)
        self.duration = float(t.max()) if t.size else 0.0

    def at(self, t):
        """Joint values at ``t`` [s] and whether the move is finished."""
        if self.duration <= 0.0:
            return self.goal.copy(), True
        s = (t - self.t0) / self.duration
        return self.start + quintic(s) * (self.goal - self.start), s >= 1.0


class JointGroup(object):
    """Set-point of a group of joints (the arm's joints, or a PSM jaw): servo or interpolated move."""

    def __init__(self, q, v_max, a_max, limits=None):
        self.q = np.asarray(q, dtype=float).copy()
        self.v_max, self.a_max = v_max, a_max
        self.limits = None if limits is None else np.asarray(limits, dtype=float)
        self.move = None

    def check(self, q):
        q = np.asarray(q, dtype=float)
        if q.shape != self.q.shape or not np.all(np.isfinite(q)):
            raise ValueError('%d finite joint values expected, got %s' % (self.q.size, list(q)))
        if self.limits is not None:
            q = np.minimum(np.maximum(q, self.limits[:, 0]), self.limits[:, 1])
        return q

    def servo(self, q):
        self.move = None
        self.q = self.check(q)

    def start_move(self, goal, t):
        self.move = JointMove(self.q, self.check(goal), t, self.v_max, self.a_max)

    def step(self, t):
        """Advance the move at ``t``; returns True when a move finished in this step."""
        if self.move is None:
            return False
        self.q, done = self.move.at(t)
        if done:
            self.move = None
        return done

    @property
    def busy(self):
        return self.move is not None


class CrtkArm(object):
    """One arm under CRTK commands. ``chain`` is a :class:`dvrk_kinematics.Chain` (fk / ik).
    ``jaw`` is a :class:`JointGroup` (PSM) or None. ``ik_tolerance`` [m, rad]: a cartesian
    command whose inverse kinematics leaves a larger error is rejected."""

    def __init__(self, name, chain, q0, v_max, a_max, jaw=None, client_timeout=5.0,
                 rejoin_time=2.0, ik_tolerance=1e-3):
        if not client_timeout >= 0 or not rejoin_time > 0:
            raise ValueError('%s: client_timeout must be >= 0 s and rejoin_time > 0 s' % name)
        self.name = name
        self.chain = chain
        self.joints = JointGroup(q0, v_max, a_max, chain.limits)
        self.jaw = jaw
        self.state = OperatingState()
        self.mode = SCRIPTED
        self.client_timeout = float(client_timeout)
        self.rejoin_time = float(rejoin_time)
        self.ik_tolerance = float(ik_tolerance)
        self.last_command = None
        self.rejoin_from = None
        self.rejected = 0
        self.events = [self.snapshot()]   # operating-state snapshots to publish, oldest first
        self.last_reason = ''

    # ------------------------------------------------------------------ commands (any thread)
    def snapshot(self):
        return (self.state.state, self.state.homed, self.busy)

    @property
    def busy(self):
        return self.joints.busy or (self.jaw is not None and self.jaw.busy)

    def _take(self, t):
        if self.mode != CLIENT and self.mode != SCRIPTED:
            self.joints.move = None       # rejoin interrupted: hold where the blend is
        self.mode = CLIENT
        self.last_command = t

    def _reject(self, why):
        self.rejected += 1
        self.last_reason = why
        return False

    def state_command(self, cmd, t):
        """CRTK state command at ``t`` [s]. Home is a (zero-length) move: busy, then idle."""
        self.state.command(cmd)
        self._take(t)
        if cmd in ('disable', 'pause'):
            self.joints.move = None
            if self.jaw is not None:
                self.jaw.move = None
        if cmd == 'home':
            self.joints.start_move(self.joints.q, t)
        self.events.append(self.snapshot())

    def servo_jp(self, q, t, group='joints'):
        if not self.state.ready:
            return self._reject('servo_jp while %s' % self.state.state)
        self._take(t)
        getattr(self, group).servo(q)
        return True

    def move_jp(self, goal, t, group='joints'):
        if not self.state.ready:
            self.events.append(self.snapshot())   # the client waits for an answer
            return self._reject('move_jp while %s' % self.state.state)
        self._take(t)
        getattr(self, group).start_move(goal, t)
        self.events.append(self.snapshot())
        return True

    def solve(self, goal):
        """Joint values for the cartesian ``goal`` (4x4) from the current set-point, or None."""
        q, residual = self.chain.ik(goal, self.joints.q)
        if residual > self.ik_tolerance:
            return None
        return q

    def servo_cp(self, goal, t):
        q = self.solve(goal) if self.state.ready else None
        if q is None:
            return self._reject('servo_cp: not ready or unreachable goal')
        return self.servo_jp(q, t)

    def move_cp(self, goal, t):
        q = self.solve(goal) if self.state.ready else None
        if q is None:
            self.events.append(self.snapshot())
            return self._reject('move_cp: not ready or unreachable goal')
        return self.move_jp(q, t)

    # ------------------------------------------------------------------ tick
    def step(self, t, script_q=None, script_jaw=None):
        """Joint values (and jaw) at ``t`` [s]; ``script_q``/``script_jaw``: the script's values
        now (None when the arm has no script: it then holds)."""
        finished = self.joints.step(t)
        if self.jaw is not None:
            finished = self.jaw.step(t) or finished
        if finished and not self.busy:
            self.events.append(self.snapshot())
        if self.mode == CLIENT and self.client_timeout > 0 and script_q is not None \
                and not self.busy and self.state.state == 'ENABLED' \
                and t - self.last_command > self.client_timeout:
            self.mode, self.rejoin_from = REJOIN, (t, self.joints.q.copy(),
                                                   None if self.jaw is None else self.jaw.q.copy())
        if self.mode == REJOIN:
            t0, q_from, jaw_from = self.rejoin_from
            s = quintic((t - t0) / self.rejoin_time)
            self.joints.q = q_from + s * (np.asarray(script_q) - q_from)
            if self.jaw is not None and script_jaw is not None:
                self.jaw.q = jaw_from + s * (np.asarray(script_jaw) - jaw_from)
            if s >= 1.0:
                self.mode = SCRIPTED
        elif self.mode == SCRIPTED and script_q is not None:
            self.joints.q = np.asarray(script_q, dtype=float)
            if self.jaw is not None and script_jaw is not None:
                self.jaw.q = np.asarray(script_jaw, dtype=float)
        return self.joints.q, (None if self.jaw is None else self.jaw.q)

    def pop_events(self):
        ev, self.events = self.events, []
        return ev


def jaw_group(q0=0.0, limits=(math.radians(-20.0), math.radians(80.0))):
    """PSM jaw (one joint, dVRK range -20 .. 80 deg, 2 rad/s, 10 rad/s^2)."""
    return JointGroup([q0], 2.0, 10.0, [limits])
