"""Heartbeat policy for ``/saras/status`` (saras_msgs/ComponentStatus), ROS-agnostic.

A component reports ``(level, message)``; :meth:`Heartbeat.due` says when to publish: at the
period (1 s by default) and immediately when the level or the message changes.
"""

OK, WARN, ERROR, STALE = 0, 1, 2, 3


class Heartbeat(object):
    """Publish decision + counters of one component's status."""

    def __init__(self, component, period=1.0):
        self.component = component
        self.period = float(period)
        self.level = STALE
        self.message = 'starting'
        self.received = 0
        self.rejected = 0
        self.last_input = None
        self._last_pub = None
        self._changed = True

    def set(self, level, message):
        """Update the status; a change makes the next :meth:`due` true."""
        if level != self.level or message != self.message:
            self.level, self.message = level, message
            self._changed = True

    def input_ok(self, now):
        self.received += 1
        self.last_input = now

    def input_rejected(self):
        self.rejected += 1

    def input_age(self, now):
        return float('inf') if self.last_input is None else max(0.0, now - self.last_input)

    def due(self, now):
        """True when a status message should go out now (period elapsed or status changed)."""
        if self._changed or self._last_pub is None or now - self._last_pub >= self.period:
            self._changed = False
            self._last_pub = now
            return True
        return False
