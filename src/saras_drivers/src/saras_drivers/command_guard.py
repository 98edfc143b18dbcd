"""Plausibility checks of the targets the SARAS arm driver forwards to the robot (ROS-agnostic).

The driver is the last software stage before the arm, so it checks every target itself instead of
trusting whichever ROS publisher sent it:

* stamp: a zero stamp, a stamp in the future (beyond ``max_future``) or older than ``max_age`` is a
  rejection, never a bypass of the age check;
* workspace: the position must lie in the box ``workspace_min`` .. ``workspace_max`` [m];
* speed: a target may move at most ``max_speed * dt + step_tolerance`` [m] from the last forwarded
  one, dt the time between them [s]: the larger of their arrival interval and their stamp interval,
  so that set-points delayed together (a loaded host, a burst on the network) are not mistaken for a
  fast motion; stamps are trusted only within the age window, so a forged stamp gains at most
  ``(max_age + max_future) * max_speed`` once;
* re-synchronisation: the first target after a gap longer than ``resync_gap`` [s] (start, hold,
  reconnection, see :meth:`CommandGuard.reset`) must lie within ``max_jump`` [m] of the arm's
  measured position (fresher than ``measured_timeout``); no measured position => rejected (unless
  ``require_measurement`` is False: link tests without a state stream; the speed limit still applies).

A rejected target is not forwarded: the arm holds its last target. Times are monotonic seconds.
"""

import math

REASONS = ('zero_stamp', 'future_stamp', 'stale', 'workspace', 'speed', 'jump', 'no_measurement')


class CommandGuard(object):
    def __init__(self, workspace_min, workspace_max, max_speed, max_jump, resync_gap=0.25,
                 max_age=0.1, max_future=0.02, step_tolerance=0.0005, measured_timeout=0.25,
                 require_measurement=True):
        if len(workspace_min) != 3 or len(workspace_max) != 3 or \
                not all(lo < hi for lo, hi in zip(workspace_min, workspace_max)):
            raise ValueError('workspace_min/workspace_max: 3 values each, min < max on every axis [m]')
        for name, v in (('max_target_speed', max_speed), ('max_resync_jump', max_jump),
                        ('resync_gap', resync_gap), ('max_target_age', max_age),
                        ('max_future', max_future), ('step_tolerance', step_tolerance),
                        ('measured_timeout', measured_timeout)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError('%s must be a positive finite number' % name)
        self.lo, self.hi = tuple(workspace_min), tuple(workspace_max)
        self.max_speed, self.max_jump = float(max_speed), float(max_jump)
        self.resync_gap, self.max_age, self.max_future = resync_gap, max_age, max_future
        self.tol, self.measured_timeout = step_tolerance, measured_timeout
        self.require_measurement = bool(require_measurement)
        self.last = None            # (t, position, stamp time or None) of the last forwarded target
        self.meas = None            # (t, position) of the last measured position
        self.rejected = dict((r, 0) for r in REASONS)
        self.last_reason = ''

    def measured(self, position, t):
        if all(math.isfinite(x) for x in position):
            self.meas = (t, tuple(position))

    def reset(self):
        """Next target is a re-synchronisation (call on every (re)connection)."""
        self.last = None

    def check(self, position, stamp_age, now):
        """``(True, '')`` if the target may be forwarded, else ``(False, reason)`` (counted).

        :param stamp_age: now - header stamp [s], ``None`` for a zero stamp
        """
        reason = self._reason(position, stamp_age, now)
        if reason:
            self.rejected[reason] += 1
            self.last_reason = reason
            return False, reason
        return True, ''

    def sent(self, position, now, stamp_time=None):
        """Record a forwarded target; ``stamp_time``: its stamp on the monotonic clock of ``now``
        (check time - stamp age), None = judge the next step on arrival times only."""
        self.last = (now, tuple(position), stamp_time)

    def _reason(self, p, age, now):
        if age is None:
            return 'zero_stamp'
        if age < -self.max_future:
            return 'future_stamp'
        if age > self.max_age:
            return 'stale'
        if not all(lo <= x <= hi for x, lo, hi in zip(p, self.lo, self.hi)):
            return 'workspace'
        if self.last is not None and now - self.last[0] <= self.resync_gap:
            dt = now - self.last[0]
            if self.last[2] is not None:
                dt = max(dt, (now - age) - self.last[2])
            allowed = self.max_speed * max(0.0, dt) + self.tol
            return 'speed' if _dist(p, self.last[1]) > allowed else ''
        if self.meas is None or now - self.meas[0] > self.measured_timeout:
            return 'no_measurement' if self.require_measurement else ''
        return 'jump' if _dist(p, self.meas[1]) > self.max_jump else ''


def _dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


JAW_REASONS = ('invalid', 'zero_stamp', 'future_stamp', 'stale')


class JawGuard(object):
    """Checks of the jaw commands (``jaw_target``, one joint) the driver forwards as ``set_clip``.

    A command is forwarded only if it names exactly ``joint`` with one finite position [rad] and its
    stamp is neither zero, nor in the future beyond ``max_future``, nor older than ``max_age`` [s];
    a command equal to the last one forwarded is sent again only ``resend_period`` [s] after it (the
    teleoperation republishes a held jaw at its rate; a robot that dropped the last one as stale
    still gets it). :meth:`reset` on every (re)connection: the robot holds then, so the next command
    is sent. Times ``now`` are monotonic seconds.
    The jaw range is the robot's to enforce (``workspace`` error, counted by the driver).
    """

    def __init__(self, joint, max_age=0.1, max_future=0.02, resend_period=0.25):
        for name, v in (('max_target_age', max_age), ('jaw_resend_period', resend_period)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError('%s must be a positive finite number [s]' % name)
        self.joint, self.max_age, self.max_future = joint, float(max_age), float(max_future)
        self.resend_period = float(resend_period)
        self.last = None
        self.last_time = -math.inf
        self.rejected = dict.fromkeys(JAW_REASONS, 0)

    def check(self, names, positions, age, now):
        """-> (jaw [rad] to send or None, rejection reason or None). ``age`` [s]: now - stamp, None
        for a zero stamp. (None, None): valid but unchanged (sent less than resend_period ago)."""
        why = None
        if list(names) != [self.joint] or len(positions) != 1 or not math.isfinite(positions[0]):
            why = 'invalid'
        elif age is None:
            why = 'zero_stamp'
        elif age < -self.max_future:
            why = 'future_stamp'
        elif age > self.max_age:
            why = 'stale'
        if why:
            self.rejected[why] += 1
            return None, why
        jaw = float(positions[0])
        if jaw == self.last and now - self.last_time < self.resend_period:
            return None, None
        return jaw, None

    def sent(self, jaw, now):
        self.last, self.last_time = jaw, now

    def reset(self):
        self.last = None
