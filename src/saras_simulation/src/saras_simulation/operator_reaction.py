"""The scripted assistant surgeon's reaction to a held teleoperation (ROS-free).

The teleoperation holds the arm after any fault (console link stale, arm state stale, a set-point the
arm does not follow...) and resumes only when the operator presses and releases the clutch, as the
dVRK does. A person at the console sees the hold (operator view, haptic silence) and clutches; the
scripted surgeon does the same: ``reaction_time`` [s] after a hold is reported it presses the clutch
for ``press_time`` [s], then waits ``min_interval`` [s] before it reacts again.
"""
from saras_simulation.touchball_console import Intention


class HoldReaction(object):
    def __init__(self, reaction_time=0.5, press_time=0.3, min_interval=1.0):
        for name, v in (('reaction_time', reaction_time), ('press_time', press_time),
                        ('min_interval', min_interval)):
            if not v >= 0.0:
                raise ValueError('%s must be >= 0, got %r' % (name, v))
        self.reaction_time, self.press_time = float(reaction_time), float(press_time)
        self.min_interval = float(min_interval)
        self._press_at = None      # [s] monotonic time of the scheduled press
        self._ready_at = 0.0       # [s] no new reaction before this time
        self.reactions = 0

    def on_hold(self, now):
        """A hold was reported at monotonic time ``now`` [s]: schedule one clutch press."""
        if self._press_at is not None or now < self._ready_at:
            return False
        self._press_at = now + self.reaction_time
        self.reactions += 1
        return True

    def pressed(self, now):
        """True while the reaction's clutch press lasts."""
        if self._press_at is None:
            return False
        if now < self._press_at:
            return False
        if now < self._press_at + self.press_time:
            return True
        self._ready_at = self._press_at + self.press_time + self.min_interval
        self._press_at = None
        return False


class ReactiveSource(object):
    """A motion source (t -> Intention) whose clutch is also pressed by a :class:`HoldReaction`."""

    def __init__(self, source, reaction, clock):
        self.source, self.reaction, self.clock = source, reaction, clock
        self.servo = getattr(source, 'servo', None)

    def __call__(self, t):
        it = self.source(t)
        if not it.clutch and self.reaction.pressed(self.clock()):
            return Intention(it.position, it.orientation, it.clip_raw, True, it.clip_button)
        return it
