"""Detects the loss of the set-point source (ROS-agnostic core; the node supplies the count).

When the process that publishes the set-points dies (the teleoperation's nodelet manager), its
TCP connections close and the subscriber's publisher count drops to zero at once, however loaded
the host: an event, not a timeout, so it never fires on the set-point gaps of a busy machine.
:class:`SourceWatch` polls ``count()`` (connected publishers) and calls ``on_lost()`` once each
time the count falls from >= 1 to 0; the driver then holds the arm where it is instead of letting
it finish the last set-point, which may lead the arm by the teleoperation's ``max_lead``.
"""

import threading


class SourceWatch(object):
    def __init__(self, count, on_lost, period=0.01):
        if not period > 0:
            raise ValueError('period must be > 0 s, got %r' % (period,))
        self.count, self.on_lost, self.period = count, on_lost, float(period)
        self.connected = False
        self.losses = 0
        self._stop = threading.Event()

    def poll(self):
        """One check; True when the source was just lost (on_lost called)."""
        now_connected = self.count() > 0
        lost = self.connected and not now_connected
        self.connected = now_connected
        if lost:
            self.losses += 1
            self.on_lost()
        return lost

    def start(self):
        t = threading.Thread(target=self._run, name='source_watch', daemon=True)
        t.start()
        return t

    def stop(self):
        self._stop.set()

    def _run(self):
        while not self._stop.wait(self.period):
            self.poll()
