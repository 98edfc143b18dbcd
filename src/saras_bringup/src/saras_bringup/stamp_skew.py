"""Stamp skew of each machine's streams in a recording: header stamp vs the recorder's receive time.

A stream's skew is the 5th percentile over its messages of ``receive time - header.stamp`` [s]
(the recorder runs on the core PC, whose clock is the reference): transport latency makes it a
few milliseconds positive, and a stream stamped by design before it is sent (an audio chunk by its
first sample, a contact estimate by the pose it used) more; a publisher whose clock runs ahead of
the core PC's makes it negative by the offset, one whose clock runs behind makes it larger by the
offset. A machine's skew is the lowest of its streams' skews, the stream closest to its clock
(streams attributed to the machine of the node that published them, the bag's connection header
``callerid``). ``flag_machines`` flags the machines whose skew is outside ``[-max_ahead, +max_skew]``.

The two limits differ because the two directions differ. A message is stamped before it is sent, so
with synchronised clocks ``receive - stamp`` is never negative: a machine whose streams arrive
*before* their stamps has its clock ahead, whatever the load, and ``max_ahead`` can be tight (the
clock monitor's 2 ms). A positive skew mixes transport latency (a few ms, more on a loaded host) with
a clock running behind, so ``max_skew`` has to stay above the latency (20 ms); smaller offsets
behind are the clock monitor's to find (its four-timestamp method cancels the latency).
"""


class SkewSamples(object):
    """receive - stamp samples of one topic [s], thinned to at most ``max_samples``."""

    def __init__(self, max_samples=20000):
        self.values = []
        self.seen = 0
        self.step = 1
        self.max_samples = max_samples
        self.publishers = set()

    def add(self, t_receive, stamp):
        """One message: every step-th is kept; when full, every other kept one goes, step doubles."""
        self.seen += 1
        if self.seen % self.step:
            return
        self.values.append(t_receive - stamp)
        if len(self.values) >= self.max_samples:
            self.values = self.values[::2]
            self.step *= 2

    def low(self, fraction=0.05):
        """The ``fraction`` quantile of the samples [s] (None without samples)."""
        if not self.values:
            return None
        v = sorted(self.values)
        return v[min(len(v) - 1, int(fraction * len(v)))]


def machine_skews(topic_skews, topic_publishers, node_machine):
    """Per machine: {'skew_ms' (lowest of its streams), 'streams': {topic: skew_ms}}.

    topic_skews: {topic: skew [s]}; topic_publishers: {topic: [callerid, ...]};
    node_machine: {node name: machine}. A topic published from several machines is left out
    (its skew mixes clocks); a publisher missing from node_machine counts as machine '?'.
    """
    per = {}
    for topic, skew in topic_skews.items():
        if skew is None:
            continue
        machines = {node_machine.get(p, '?') for p in topic_publishers.get(topic, ())}
        if len(machines) != 1:
            continue
        per.setdefault(machines.pop(), {})[topic] = 1e3 * skew
    return {m: {'skew_ms': min(s.values()), 'streams': s} for m, s in per.items()}


def skewed(skew_ms, max_skew_ms, max_ahead_ms=None):
    """True when a machine's skew [ms] is below -max_ahead_ms (default: max_skew_ms) or above max_skew_ms."""
    ahead = max_skew_ms if max_ahead_ms is None else max_ahead_ms
    return skew_ms < -ahead or skew_ms > max_skew_ms


def flag_machines(per_machine, max_skew_ms, max_ahead_ms=None):
    """Problems (one line per machine) whose stamp skew is outside [-max_ahead_ms, +max_skew_ms]
    (max_ahead_ms None: +-max_skew_ms)."""
    problems = []
    for machine, row in sorted(per_machine.items()):
        skew = row['skew_ms']
        if skewed(skew, max_skew_ms, max_ahead_ms):
            ahead = skew < 0
            limit = max_skew_ms if not ahead or max_ahead_ms is None else max_ahead_ms
            problems.append('machine %s: header stamps %.1f ms %s the recorder\'s clock (lowest of %d streams; '
                            'limit %.0f ms): check its clock (clock_monitor, chrony)'
                            % (machine, abs(skew), 'ahead of' if ahead else 'behind', len(row['streams']), limit))
    return problems


def format_machines(per_machine, max_skew_ms, max_ahead_ms=None):
    lines = ['%-14s %10s %8s  %s' % ('machine', 'skew[ms]', 'streams', 'status')]
    for machine, row in sorted(per_machine.items()):
        status = 'STAMP SKEW' if skewed(row['skew_ms'], max_skew_ms, max_ahead_ms) else 'ok'
        lines.append('%-14s %10.1f %8d  %s' % (machine, row['skew_ms'], len(row['streams']), status))
    return '\n'.join(lines)
