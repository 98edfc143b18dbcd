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

import threading
import time


class MasterWatch(object):
    def __init__(self, probe, on_lost, period=0.2, grace=1.0, clock=time.monotonic):
        if not (period > 0 and grace >= 0):
            raise ValueError('period must be > 0 s and grace >= 0 s')
        self.probe, self.on_lost = probe, on_lost
        self.period, self.grace, self.clock = period, grace, clock
        self.pid = None
        self.unreachable_since = None
        self.lost = None              # reason, once lost
        self._stop = threading.Event()

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

    def start(self):
        t = threading.Thread(target=self._run, name='master_watch', daemon=True)
        t.start()
        return t

    def stop(self):
        self._stop.set()

    def _run(self):
        while not self._stop.wait(self.period):
            if self.poll():
                return
