"""Per-packet impairment model of one link direction (ROS-free).

An :class:`Impairment` decides, for each packet (UDP datagram) or chunk (TCP read) arriving at the
relay, whether it is dropped and, if not, when it leaves:

* **delay** ``delay_s``: fixed one-way delay added to every packet [s].
* **jitter** ``jitter_s``: bounded variation around the delay [s]. ``uniform``: uniform in
  ``[delay - jitter, delay + jitter]``; ``normal``: normal with sigma ``jitter / 2``, truncated to
  the same interval. The result is never below 0.
* **random loss** ``loss``: independent loss probability per packet [0..1].
* **bursty loss** (Gilbert-Elliott two-state Markov chain, evaluated per packet, independent of the
  random loss; a packet is lost when either drops it): the chain is in state Good or Bad; before
  each packet it moves Good->Bad with probability ``p_good_bad`` and Bad->Good with probability
  ``p_bad_good``; the packet is then lost with probability ``loss_good`` in Good and ``loss_bad`` in
  Bad. Stationary share of Bad: ``pi_bad = p_good_bad / (p_good_bad + p_bad_good)``; mean loss
  ``(1 - pi_bad) loss_good + pi_bad loss_bad``; mean sojourn in Bad ``1 / p_bad_good`` packets
  (with ``loss_bad = 1`` that is the mean burst length). ``p_good_bad = 0`` disables it.
* **reordering**: independent per-packet delays reorder packets whenever the jitter exceeds the
  packet spacing; in addition, with probability ``reorder_probability`` a packet is held an extra
  ``reorder_gap_s`` so that the packets behind it overtake it.

TCP chunks use only delay and jitter, with departures kept in arrival order (a byte stream cannot
be reordered or lose bytes without breaking it; loss on a real link shows up as TCP retransmission
delay, which delay and jitter model): see :meth:`Impairment.stream_release`.
"""
import math
import random
from dataclasses import dataclass


@dataclass(frozen=True)
class ImpairmentConfig:
    """Parameters of one link direction; units in the names (s, probability 0..1)."""
    delay_s: float = 0.0
    jitter_s: float = 0.0
    jitter_distribution: str = 'uniform'
    loss: float = 0.0
    p_good_bad: float = 0.0
    p_bad_good: float = 1.0
    loss_good: float = 0.0
    loss_bad: float = 1.0
    reorder_probability: float = 0.0
    reorder_gap_s: float = 0.0

    def __post_init__(self):
        for name in ('delay_s', 'jitter_s', 'reorder_gap_s'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError('%s = %r: a finite number >= 0 [s] expected' % (name, value))
        for name in ('loss', 'p_good_bad', 'p_bad_good', 'loss_good', 'loss_bad',
                     'reorder_probability'):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError('%s = %r: a probability in [0, 1] expected' % (name, value))
        if self.jitter_distribution not in ('uniform', 'normal'):
            raise ValueError("jitter_distribution = %r: 'uniform' or 'normal' expected"
                             % (self.jitter_distribution,))
        if self.p_good_bad > 0.0 and self.p_bad_good == 0.0:
            raise ValueError('p_bad_good = 0 with p_good_bad > 0 traps the chain in Bad')
        if self.reorder_probability > 0.0 and self.reorder_gap_s == 0.0:
            raise ValueError('reorder_probability > 0 needs reorder_gap_s > 0')

    @property
    def bursty(self):
        return self.p_good_bad > 0.0

    def expected_loss(self):
        """Long-run loss probability of random and bursty loss together."""
        burst = 0.0
        if self.bursty:
            pi_bad = self.p_good_bad / (self.p_good_bad + self.p_bad_good)
            burst = (1.0 - pi_bad) * self.loss_good + pi_bad * self.loss_bad
        return 1.0 - (1.0 - self.loss) * (1.0 - burst)


class Impairment:
    """Draws drop decisions and departure times for one link direction."""

    def __init__(self, config, seed=None):
        self.config = config
        self._rng = random.Random(seed)
        self._bad = False
        self._last_stream_release = -math.inf

    def _bursty_drop(self):
        c = self.config
        if not c.bursty:
            return False
        if self._bad:
            self._bad = self._rng.random() >= c.p_bad_good
        else:
            self._bad = self._rng.random() < c.p_good_bad
        return self._rng.random() < (c.loss_bad if self._bad else c.loss_good)

    def drop(self):
        """True if the next packet is lost (advances the Gilbert-Elliott chain)."""
        burst = self._bursty_drop()
        random_loss = self.config.loss > 0.0 and self._rng.random() < self.config.loss
        return burst or random_loss

    def delay(self):
        """One draw of the one-way delay [s] (fixed delay and jitter)."""
        c = self.config
        if c.jitter_s == 0.0:
            return c.delay_s
        if c.jitter_distribution == 'uniform':
            offset = self._rng.uniform(-c.jitter_s, c.jitter_s)
        else:
            offset = self._rng.gauss(0.0, c.jitter_s / 2.0)
            while abs(offset) > c.jitter_s:
                offset = self._rng.gauss(0.0, c.jitter_s / 2.0)
        return max(0.0, c.delay_s + offset)

    def datagram_release(self, arrival):
        """Departure time of a datagram that arrived at ``arrival`` [s], or None if dropped."""
        if self.drop():
            return None
        release = arrival + self.delay()
        c = self.config
        if c.reorder_probability > 0.0 and self._rng.random() < c.reorder_probability:
            release += c.reorder_gap_s
        return release

    def stream_release(self, arrival):
        """Departure time of a stream chunk: delayed and jittered, never before the last one."""
        release = max(arrival + self.delay(), self._last_stream_release)
        self._last_stream_release = release
        return release


# Delay histogram bin upper edges [s]; the last bin is open.
HISTOGRAM_EDGES_S = (0.001, 0.002, 0.005, 0.010, 0.020, 0.050, 0.100, 0.200, 0.500, 1.0)


class LinkStats:
    """Counters of one link direction: received, sent, dropped, reordered, delay histogram."""

    def __init__(self):
        self.received = 0
        self.sent = 0
        self.dropped = 0
        self.reordered = 0
        self.bytes_sent = 0
        self.histogram = [0] * (len(HISTOGRAM_EDGES_S) + 1)
        self.delay_min_s = math.inf
        self.delay_max_s = 0.0
        self._delay_sum_s = 0.0
        self._highest_sent_seq = -1

    def on_received(self):
        """Counts an arrival and returns its sequence number."""
        self.received += 1
        return self.received - 1

    def on_dropped(self):
        self.dropped += 1

    def on_sent(self, seq, delay_s, size):
        """Counts a departure; a packet leaving after a later arrival counts as reordered."""
        self.sent += 1
        self.bytes_sent += size
        if seq < self._highest_sent_seq:
            self.reordered += 1
        else:
            self._highest_sent_seq = seq
        self._delay_sum_s += delay_s
        self.delay_min_s = min(self.delay_min_s, delay_s)
        self.delay_max_s = max(self.delay_max_s, delay_s)
        for i, edge in enumerate(HISTOGRAM_EDGES_S):
            if delay_s < edge:
                self.histogram[i] += 1
                return
        self.histogram[-1] += 1

    @property
    def delay_mean_s(self):
        return self._delay_sum_s / self.sent if self.sent else math.nan

    def histogram_labels(self):
        """Bin labels in ms, e.g. '<1', '<2', ..., '>=1000'."""
        labels = ['<%g' % (1e3 * e) for e in HISTOGRAM_EDGES_S]
        return labels + ['>=%g' % (1e3 * HISTOGRAM_EDGES_S[-1])]

    def as_dict(self):
        return {
            'received': self.received, 'sent': self.sent, 'dropped': self.dropped,
            'reordered': self.reordered, 'bytes_sent': self.bytes_sent,
            'delay_min_ms': 1e3 * self.delay_min_s if self.sent else math.nan,
            'delay_mean_ms': 1e3 * self.delay_mean_s,
            'delay_max_ms': 1e3 * self.delay_max_s if self.sent else math.nan,
            'delay_histogram_ms': dict(zip(self.histogram_labels(), self.histogram)),
        }
