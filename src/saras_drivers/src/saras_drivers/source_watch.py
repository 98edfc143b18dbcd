"""Detects the loss of the set-point source (ROS-agnostic core; the node supplies the count).

When the process that publishes the set-points dies (the teleoperation's nodelet manager), its
TCP connections close and the subscriber's publisher count drops to zero at once, however loaded
the host: an event, not a timeout, so it never fires on the set-point gaps of a busy machine.
:class:`SourceWatch` polls ``count()`` (connected publishers) and calls ``on_lost()`` once each
time the count falls from >= 1 to 0; the driver then holds the arm where it is instead of letting
it finish the last set-point, which may lead the arm by the teleoperation's ``max_lead``.
"""

from saras_drivers.poller import Poller


class SourceWatch(Poller):
    def __init__(self, count, on_lost, period=0.01):
        Poller.__init__(self, period, 'source_watch', once=False)  # the source may come back
        self.count, self.on_lost = count, on_lost
        self.connected = False
        self.losses = 0

    def poll(self):
        """One check; True when the source was just lost (on_lost called)."""
        now_connected = self.count() > 0
        lost = self.connected and not now_connected
        self.connected = now_connected
        if lost:
            self.losses += 1
            self.on_lost()
        return lost
