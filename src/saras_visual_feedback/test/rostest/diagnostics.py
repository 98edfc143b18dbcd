"""Test helper: records this package's statuses from /diagnostics."""
import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: F401 (levels for the tests)


class DiagnosticsRecorder(object):
    """Statuses (hardware_id visual_feedback) whose name starts with `node` (e.g. 'visual_feedback',
    'mesa_left/contact_forces'), oldest first; values() gives a status's key/values as a dict."""

    def __init__(self, node):
        self.node = node
        self.statuses = []
        self.sub = rospy.Subscriber('/diagnostics', DiagnosticArray, self._cb, queue_size=50)

    def _cb(self, msg):
        for s in msg.status:
            if s.hardware_id == 'visual_feedback' and s.name.startswith(self.node + ':'):
                self.statuses.append(s)

    @staticmethod
    def values(status):
        return {v.key: v.value for v in status.values}
