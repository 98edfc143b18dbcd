"""ROS adapters shared by the nodes in ``scripts/`` (the only module that imports rospy).

Conversions between ROS messages and 4x4 numpy transforms, start-up parameter validation
(a bad value is a fatal error naming the parameter; the node exits non-zero), and a latched
"last valid pose" holder that rejects malformed messages with a counter and a throttled error.
"""
import sys
import threading

import numpy as np
import rospy
from geometry_msgs.msg import TransformStamped

from .transforms import make_transform, quaternion_from_transform, transform_from_rpy
from scipy.spatial.transform import Rotation


def fatal(node, msg):
    """Log a fatal start-up error and exit with status 2."""
    rospy.logfatal('%s: %s', node, msg)
    sys.exit(2)


def param(node, name, default, kind=None, check=None, what=''):
    """Read ``~name`` once; ``kind`` converts, ``check(value)`` validates; fatal otherwise."""
    value = rospy.get_param('~' + name, default)
    try:
        if kind is not None:
            value = kind(value)
        if check is not None and not check(value):
            raise ValueError('expected %s' % what)
    except (TypeError, ValueError) as exc:
        fatal(node, 'invalid parameter ~%s = %r (%s)' % (name, value, exc))
    return value


def pose_to_matrix(pose):
    """geometry_msgs/Pose -> 4x4; raises ValueError on NaN or a zero quaternion."""
    p, q = pose.position, pose.orientation
    v = np.array([p.x, p.y, p.z, q.x, q.y, q.z, q.w], dtype=float)
    if not np.all(np.isfinite(v)):
        raise ValueError('pose contains NaN or inf')
    n = np.linalg.norm(v[3:])
    if abs(n - 1.0) > 0.01:
        raise ValueError('pose quaternion norm %.4f is not 1' % n)
    return make_transform(Rotation.from_quat(v[3:] / n).as_matrix(), v[:3])


def matrix_to_transform(T, parent, child, stamp=None):
    """4x4 -> geometry_msgs/TransformStamped ``parent -> child``."""
    ts = TransformStamped()
    ts.header.stamp = stamp or rospy.Time.now()
    ts.header.frame_id = parent
    ts.child_frame_id = child
    ts.transform.translation.x, ts.transform.translation.y, ts.transform.translation.z = (float(v) for v in T[:3, 3])
    q = quaternion_from_transform(T)
    ts.transform.rotation.x, ts.transform.rotation.y, ts.transform.rotation.z, ts.transform.rotation.w = (float(v) for v in q)
    return ts


def entry_to_transform(entry, stamp=None):
    """World-frame YAML entry -> TransformStamped."""
    return matrix_to_transform(transform_from_rpy(entry['xyz'], entry['rpy']), entry['parent'], entry['child'], stamp)


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
