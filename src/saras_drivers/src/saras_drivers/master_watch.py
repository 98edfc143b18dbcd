"""Detects the loss of the ROS master (ROS-agnostic core; the node supplies the probe).

A node keeps its existing topic connections when the master dies, but a master restarted on the
same port knows none of them: nothing re-registers, so nothing can be inspected, recorded or
restarted any more. The platform therefore treats both as a fault that ends in a controlled safe
stop (the arm holds, the recording closes, a clear message), not as something to ride through.

:class:`MasterWatch` polls ``probe()`` (returns the master's PID, raises when unreachable) every
``period`` seconds and calls ``on_lost(reason)`` once: at once when the connection is refused (no
process listens on the master's port: it died) or its PID changed (a restarted master), and when
it has been unreachable otherwise (timeouts: a loaded or partitioned host) for ``grace`` seconds.
"""

import time

from saras_drivers.poller import Poller


class MasterWatch(Poller):
    def __init__(self, probe, on_lost, period=0.2, grace=1.0, clock=time.monotonic):
        if not grace >= 0:
            raise ValueError('grace must be >= 0 s, got %r' % (grace,))
        Poller.__init__(self, period, 'master_watch', once=True)    # a lost master is final
        self.probe, self.on_lost = probe, on_lost
        self.grace, self.clock = grace, clock
        self.pid = None
        self.unreachable_since = None
        self.lost = None              # reason, once lost

    def poll(self):
        """One check; returns the loss reason (also passed to on_lost once) or None."""
        if self.lost:
            return self.lost
        now = self.clock()
        try:
            pid = self.probe()
        except ConnectionRefusedError as e:
            return self._lose('ROS master gone (%s)' % e)
        except Exception as e:      # any other transport error means unreachable
            if self.unreachable_since is None:
                self.unreachable_since = now
            if now - self.unreachable_since >= self.grace:
                return self._lose('ROS master unreachable for %.1f s (%s)' % (now - self.unreachable_since, e))
            return None
        self.unreachable_since = None
        if self.pid is not None and pid != self.pid:
            return self._lose('ROS master restarted (pid %s -> %s): this node is no longer registered'
                              % (self.pid, pid))
        self.pid = pid
        return None

    def _lose(self, reason):
        self.lost = reason
        self.on_lost(reason)
        return reason
