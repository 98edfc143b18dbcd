"""Stamp skew of each machine's streams in a recording: header stamp vs the recorder's receive time.

A stream's skew is the 5th percentile over its messages of ``receive time - header.stamp`` [s]
(the recorder runs on the core PC, whose clock is the reference): transport latency makes it a
few milliseconds positive, and a stream stamped by design before it is sent (an audio chunk by its
first sample, a contact estimate by the pose it used) more; a publisher whose clock runs ahead of
the core PC's makes it negative by the offset, one whose clock runs behind makes it larger by the
offset. A machine's skew is the lowest of its streams' skews, the stream closest to its clock
(streams attributed to the machine of the node that published them, the bag's connection header
``callerid``). ``flag_machines`` flags the machines whose skew is outside ``[-max_skew, +max_skew]``.
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


def flag_machines(per_machine, max_skew_ms):
    """Problems (one line per machine) whose stamp skew is beyond +-max_skew_ms."""
    problems = []
    for machine, row in sorted(per_machine.items()):
        skew = row['skew_ms']
        if abs(skew) > max_skew_ms:
            how = 'ahead of' if skew < 0 else 'behind'
            problems.append('machine %s: header stamps %.1f ms %s the recorder\'s clock (lowest of %d streams; '
                            'limit %.0f ms): check its clock (clock_monitor, chrony)'
                            % (machine, abs(skew), how, len(row['streams']), max_skew_ms))
    return problems


def format_machines(per_machine, max_skew_ms):
    lines = ['%-14s %10s %8s  %s' % ('machine', 'skew[ms]', 'streams', 'status')]
    for machine, row in sorted(per_machine.items()):
        status = 'STAMP SKEW' if abs(row['skew_ms']) > max_skew_ms else 'ok'
        lines.append('%-14s %10.1f %8d  %s' % (machine, row['skew_ms'], len(row['streams']), status))
    return '\n'.join(lines)
