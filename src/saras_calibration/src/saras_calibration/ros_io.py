"""ROS adapters shared by the nodes in ``scripts/`` (the only module of the package importing rospy).

Message conversions come from :mod:`saras_common.transforms` and parameters are read with
:mod:`saras_common.params`; this module adds the frames-file entry -> TransformStamped conversion
and a "last valid pose" holder that rejects malformed messages with a counter and a throttled error.
"""
import threading

import rospy
from saras_common.transforms import pose_to_matrix, transform_from_rpy, transform_stamped


def entry_to_transform(entry, stamp=None):
    """World-frame YAML entry -> TransformStamped ``parent -> child`` (stamp default: now)."""
    return transform_stamped(entry['parent'], entry['child'], transform_from_rpy(entry['xyz'], entry['rpy']),
                             stamp or rospy.Time.now())


class LatestPose:
    """Subscribes to a PoseStamped topic and keeps the last valid pose (thread-safe).

    Malformed poses (NaN, bad quaternion, unexpected frame) are rejected, counted and logged
    (throttled); they never replace the last valid pose.
    """

    def __init__(self, node, topic, expected_frame=None):
        from geometry_msgs.msg import PoseStamped
        self.node, self.topic, self.expected_frame = node, topic, expected_frame
        self.lock = threading.Lock()
        self.T, self.stamp, self.received_at, self.frame = None, None, None, None
        self.received = 0
        self.rejected = 0
        self.sub = rospy.Subscriber(topic, PoseStamped, self._cb, queue_size=1, tcp_nodelay=True)

    def _cb(self, msg):
        try:
            T = pose_to_matrix(msg.pose)
            if self.expected_frame and msg.header.frame_id and msg.header.frame_id != self.expected_frame:
                raise ValueError('frame %r, expected %r' % (msg.header.frame_id, self.expected_frame))
        except ValueError as exc:
            with self.lock:
                self.rejected += 1
            rospy.logerr_throttle(2.0, '%s: rejected pose on %s: %s (%d rejected)'
                                  % (self.node, self.topic, exc, self.rejected))
            return
        with self.lock:
            self.T, self.stamp, self.frame = T, msg.header.stamp, msg.header.frame_id
            self.received_at = rospy.Time.now()
            self.received += 1

    def counts(self):
        """(received, rejected) message counts."""
        with self.lock:
            return self.received, self.rejected

    def get(self, max_age):
        """(T, stamp) of the last valid pose if received within ``max_age`` [s], else raise
        ValueError with the reason."""
        with self.lock:
            if self.T is None:
                raise ValueError('no valid pose received on %s yet' % self.topic)
            age = (rospy.Time.now() - self.received_at).to_sec()
            if age > max_age:
                raise ValueError('last pose on %s is %.2f s old (> %.2f s)' % (self.topic, age, max_age))
            return self.T.copy(), self.stamp
