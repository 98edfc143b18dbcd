"""The polling thread of the driver's watches (MasterWatch, SourceWatch): ROS-agnostic.

A subclass implements ``poll()``; :meth:`Poller.start` calls it every ``period`` seconds on a daemon
thread until :meth:`Poller.stop`, or until ``poll()`` returns a true value when ``once`` (a watch
whose event is final, e.g. the master lost for good).
"""

import threading


class Poller(object):
    def __init__(self, period, name, once):
        if not period > 0:
            raise ValueError('period must be > 0 s, got %r' % (period,))
        self.period, self._name, self._once = float(period), name, bool(once)
        self._stop = threading.Event()

    def poll(self):
        raise NotImplementedError

    def start(self):
        t = threading.Thread(target=self._run, name=self._name, daemon=True)
        t.start()
        return t

    def stop(self):
        self._stop.set()

    def _run(self):
        while not self._stop.wait(self.period):
            if self.poll() and self._once:
                return
