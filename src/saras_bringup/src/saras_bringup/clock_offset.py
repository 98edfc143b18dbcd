"""Clock offsets between machines by the NTP four-timestamp method (ROS-free core).

One exchange between the monitor (core PC) and a responder (another machine):

* ``t1`` request sent (monitor clock), ``t2`` request received (responder clock),
* ``t3`` reply sent (responder clock), ``t4`` reply received (monitor clock).

``offset = ((t2 - t1) + (t3 - t4)) / 2`` is the responder clock minus the monitor clock, exact
when the two one-way delays are equal; ``delay = (t4 - t1) - (t3 - t2)`` is the round trip spent
on the network (responder's processing removed). An asymmetry ``a`` of the one-way delays biases the
offset by ``a / 2``, at most ``delay / 2``; the exchange with the smallest delay in a window of
recent ones therefore gives the best estimate (best-of-N minimum-delay filter, as NTP's clock
filter). All times in seconds of wall-clock time (never simulated time).
"""
from collections import deque
from dataclasses import dataclass

# Levels of a machine's clock status (same values as diagnostic_msgs/DiagnosticStatus).
OK, WARN, ERROR, STALE = 0, 1, 2, 3


@dataclass(frozen=True)
class Exchange:
    """One request/reply exchange; times in s (t1, t4: monitor clock; t2, t3: responder clock)."""
    t1: float
    t2: float
    t3: float
    t4: float

    @property
    def offset(self):
        """Responder clock minus monitor clock [s]."""
        return ((self.t2 - self.t1) + (self.t3 - self.t4)) / 2.0

    @property
    def delay(self):
        """Round-trip network delay [s]."""
        return (self.t4 - self.t1) - (self.t3 - self.t2)


def best_of(exchanges):
    """The exchange of smallest delay (None if there is none)."""
    return min(exchanges, key=lambda e: e.delay, default=None)


class MachineClock:
    """The recent exchanges with one machine and its best offset estimate."""

    def __init__(self, window):
        if window < 1:
            raise ValueError('window = %r: at least 1 exchange' % (window,))
        self._exchanges = deque(maxlen=window)
        self.last_reply = None  # monitor time of the last reply [s]
        self.count = 0

    def add(self, exchange):
        self._exchanges.append(exchange)
        self.last_reply = exchange.t4
        self.count += 1

    def best(self):
        return best_of(self._exchanges)

    @property
    def samples(self):
        return len(self._exchanges)


@dataclass(frozen=True)
class MonitorConfig:
    threshold_s: float = 0.002  # |offset| above this warns [s]
    window: int = 16            # exchanges per machine the estimate is taken from
    timeout_s: float = 3.0      # no reply for this long: stale [s]; also drops unanswered requests
    max_delay_s: float = 0.5    # exchanges with a larger round trip are discarded [s]

    def __post_init__(self):
        for name in ('threshold_s', 'timeout_s', 'max_delay_s'):
            if not getattr(self, name) > 0.0:
                raise ValueError('%s = %r: > 0 [s] expected' % (name, getattr(self, name)))
        if self.window < 1:
            raise ValueError('window = %r: >= 1 expected' % (self.window,))


@dataclass(frozen=True)
class ClockStatus:
    machine: str
    level: int
    message: str
    offset_s: float = float('nan')
    delay_s: float = float('nan')
    samples: int = 0


class ClockMonitorCore:
    """Matches replies to requests and rates every machine's offset against the threshold."""

    def __init__(self, config, expected=()):
        self.config = config
        self._pending = {}  # request id -> t1
        self._next_id = 0
        self._clocks = {name: MachineClock(config.window) for name in expected}
        self.discarded = 0  # replies to unknown/expired requests or with too large a delay

    def new_request(self, t1):
        """Registers a request sent at t1 (monitor clock) and returns its id."""
        self._expire(t1)
        request_id = self._next_id
        self._next_id += 1
        self._pending[request_id] = t1
        return request_id

    def _expire(self, now):
        old = [i for i, t1 in self._pending.items() if now - t1 > self.config.timeout_s]
        for i in old:
            del self._pending[i]

    def on_reply(self, request_id, machine, t2, t3, t4):
        """A reply of `machine` to request_id; returns the Exchange, or None if discarded."""
        t1 = self._pending.get(request_id)
        exchange = None if t1 is None else Exchange(t1, t2, t3, t4)
        if exchange is None or not 0.0 <= exchange.delay <= self.config.max_delay_s:
            self.discarded += 1
            return None
        clock = self._clocks.get(machine)
        if clock is None:
            clock = self._clocks[machine] = MachineClock(self.config.window)
        clock.add(exchange)
        return exchange

    @property
    def machines(self):
        return sorted(self._clocks)

    def status(self, machine, now):
        """The ClockStatus of `machine` at monitor time `now`."""
        clock = self._clocks.get(machine)
        best = clock.best() if clock else None
        if best is None:
            return ClockStatus(machine, STALE, 'no reply from its clock responder')
        values = dict(offset_s=best.offset, delay_s=best.delay, samples=clock.samples)
        if now - clock.last_reply > self.config.timeout_s:
            return ClockStatus(machine, STALE, 'no reply for %.1f s' % (now - clock.last_reply),
                               **values)
        text = 'offset %+.3f ms (round trip %.3f ms)' % (1e3 * best.offset, 1e3 * best.delay)
        if abs(best.offset) > self.config.threshold_s:
            return ClockStatus(machine, WARN, text + ' above %.3f ms'
                               % (1e3 * self.config.threshold_s), **values)
        return ClockStatus(machine, OK, text, **values)
