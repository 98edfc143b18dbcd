#!/usr/bin/env python3
"""Fast-moving tools seen by LATE images, for visual_feedback_late_stamps.test (issue 7).

Two tools move at up to 13 cm/s in front of the simulated stereo endoscope of scene.py:
* ``fast_pose``: its tip pose (frame ``world``) is published at ~250 Hz on /fast/ee_pose, each
  sample stamped with the time its value belongs to;
* ``fast_frame``: its pose is constant (origin of TF frame ``fast_frame``, 50 Hz), the frame moves
  (TF world -> fast_frame broadcast at ~250 Hz).
Images (black, bgr8) and camera_info are published at ~image_rate (30 Hz) with header.stamp
~image_delay (0.05 s) in the past, as from a camera whose frames reach the computer late. The
drawn tips must be where the tools were at the image stamp; the checker computes that from the
same analytic motion below.

Private parameters: ~image_rate [Hz] (30), ~image_delay [s] (0.05).
"""
import math

import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped, TransformStamped
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Float64MultiArray

import scene

# Distances published for [fast_pose, fast_frame] [m]: red and green with the default thresholds.
DISTANCES = [0.003, 0.05]
EXPECTED_BGR = {'fast_pose': (0, 0, 255), 'fast_frame': (0, 255, 0)}


def tip_world(tool, t):
    """Tip of @p tool in world [m] at time t [s] (analytic motion, peak speed 0.126 / 0.113 m/s)."""
    if tool == 'fast_pose':
        return (0.05 + 0.02 * math.sin(2.0 * math.pi * 1.0 * t), 0.02, 0.10)
    return (0.05 + 0.015 * math.cos(2.0 * math.pi * 1.2 * t), -0.02, 0.10)


class FastTool:
    def __init__(self):
        self.image_rate = rospy.get_param('~image_rate', 30.0)
        self.image_delay = rospy.Duration.from_sec(rospy.get_param('~image_delay', 0.05))
        self.pose_pub = rospy.Publisher('/fast/ee_pose', PoseStamped, queue_size=10, tcp_nodelay=True)
        self.frame_pose_pub = rospy.Publisher('/fast_frame/ee_pose', PoseStamped, queue_size=10, tcp_nodelay=True)
        self.dist_pub = rospy.Publisher('/collision/distances', Float64MultiArray, queue_size=1)
        self.image_pubs = [rospy.Publisher('/endoscope/%s/image_raw' % e, Image, queue_size=2) for e in ('left', 'right')]
        self.info_pubs = [rospy.Publisher('/endoscope/%s/camera_info' % e, CameraInfo, queue_size=2)
                          for e in ('left', 'right')]
        self.tf = tf2_ros.TransformBroadcaster()
        self.static_tf = tf2_ros.StaticTransformBroadcaster()
        statics = []
        for child in ('endoscope/left_optical_frame', 'endoscope/right_optical_frame'):
            parent, xyz, rpy = scene.FRAMES[child]
            s = TransformStamped()
            s.header.stamp = rospy.Time.now()
            s.header.frame_id, s.child_frame_id = parent, child
            s.transform.translation.x, s.transform.translation.y, s.transform.translation.z = xyz
            (s.transform.rotation.x, s.transform.rotation.y, s.transform.rotation.z,
             s.transform.rotation.w) = scene.quaternion(*rpy)
            statics.append(s)
        self.static_tf.sendTransform(statics)
        self.black = bytes(3 * scene.WIDTH * scene.HEIGHT)
        self.count = 0

    def fast(self, event):
        try:
            self._fast(event)
        except rospy.ROSException:  # publishers closed at shutdown
            pass

    def _fast(self, _event):
        """~250 Hz: the moving pose and the moving TF frame, stamped with the time of their values."""
        now = rospy.Time.now()
        t = now.to_sec()
        p = PoseStamped()
        p.header.stamp, p.header.frame_id = now, 'world'
        p.pose.position.x, p.pose.position.y, p.pose.position.z = tip_world('fast_pose', t)
        p.pose.orientation.w = 1.0
        self.pose_pub.publish(p)
        tr = TransformStamped()
        tr.header.stamp, tr.header.frame_id, tr.child_frame_id = now, 'world', 'fast_frame'
        tr.transform.translation.x, tr.transform.translation.y, tr.transform.translation.z = tip_world('fast_frame', t)
        tr.transform.rotation.w = 1.0
        self.tf.sendTransform(tr)
        self.count += 1
        if self.count % 5 == 0:  # 50 Hz: constant pose in the moving frame, and the distances
            q = PoseStamped()
            q.header.stamp, q.header.frame_id = now, 'fast_frame'
            q.pose.orientation.w = 1.0
            self.frame_pose_pub.publish(q)
            self.dist_pub.publish(Float64MultiArray(data=DISTANCES))

    def images(self, event):
        try:
            self._images(event)
        except rospy.ROSException:  # publishers closed at shutdown
            pass

    def _images(self, _event):
        stamp = rospy.Time.now() - self.image_delay
        for e, eye in enumerate(('left', 'right')):
            info, img = scene.eye_messages(eye, stamp, self.black)
            self.info_pubs[e].publish(info)
            self.image_pubs[e].publish(img)

    def run(self):
        timers = [rospy.Timer(rospy.Duration(0.004), self.fast),
                  rospy.Timer(rospy.Duration(1.0 / self.image_rate), self.images)]
        rospy.spin()
        for t in timers:
            t.shutdown()


if __name__ == '__main__':
    rospy.init_node('fast_tool')
    FastTool().run()
