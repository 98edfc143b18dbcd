"""/diagnostics as records the rostest nodes filter: node name, task, level, message, counters."""
import collections

import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

OK, WARN, ERROR, STALE = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR, DiagnosticStatus.STALE


class Status(collections.namedtuple('Status', 'component task level message values')):
    """One DiagnosticStatus; ``component`` is the publishing node's name (without the leading /)."""

    def count(self, *prefixes):
        """Sum of the integer values whose key starts with one of ``prefixes``."""
        return sum(int(float(v)) for k, v in self.values.items() if k.startswith(prefixes))

    @property
    def rejected(self):
        """Inputs rejected or dropped, whatever the reason."""
        return self.count('rejected', 'dropped')


def subscribe(out, queue_size=100):
    """Append a :class:`Status` to ``out`` for every status published on /diagnostics."""
    def on_array(msg):
        for s in msg.status:
            node, _, task = s.name.partition(': ')
            out.append(Status(node, task, s.level, s.message, {kv.key: kv.value for kv in s.values}))
    return rospy.Subscriber('/diagnostics', DiagnosticArray, on_array, queue_size=queue_size)
