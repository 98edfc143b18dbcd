#!/usr/bin/env python3
"""Small simulated scene for the VisualFeedback rostests: stereo images + camera_info, static TF,
tool poses and collision distances (see scene.py).

Private parameters: ~rate [Hz] (image rate, default 30), ~bad_input (bool, default false: when
true also publishes truncated images, uncalibrated camera_info, NaN poses and short distance
arrays between good ones),
~images (bool, default true: false publishes only TF, poses and distances, for use with the real
saras_simulation/endoscope_sim).
"""
import math

import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped, TransformStamped
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Float64MultiArray

import scene


class FakeEndoscope:
    def __init__(self):
        self.rate = rospy.get_param('~rate', 30.0)
        self.bad_input = rospy.get_param('~bad_input', False)
        self.images = rospy.get_param('~images', True)
        self.image_pubs = [rospy.Publisher('/endoscope/%s/image_raw' % e, Image, queue_size=2) for e in ('left', 'right')]
        self.info_pubs = [rospy.Publisher('/endoscope/%s/camera_info' % e, CameraInfo, queue_size=2)
                          for e in ('left', 'right')]
        self.pose_pubs = {n: rospy.Publisher(t[0], PoseStamped, queue_size=1) for n, t in scene.TOOLS.items()}
        self.dist_pub = rospy.Publisher('/collision/distances', Float64MultiArray, queue_size=1)
        self.tf = tf2_ros.StaticTransformBroadcaster()
        self.tf.sendTransform([self._static(child) for child in scene.FRAMES])
        # A dark vertical gradient (no pure red/yellow/green anywhere).
        row = bytes([20, 30, 40]) * scene.WIDTH
        self.data = [b''.join(bytes([20 + (y % 40), 30, 40 + e * 10]) * scene.WIDTH for y in range(scene.HEIGHT))
                     for e in (0, 1)]
        del row
        # Tool tips in their pose frames (constant): computed once.
        self.tips = {name: tuple(float(c) for c in scene.to_frame(frame, tip_world))
                     for name, (_, frame, tip_world, _, _) in scene.TOOLS.items()}
        self.count = 0

    @staticmethod
    def _static(child):
        parent, xyz, rpy = scene.FRAMES[child]
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = parent
        t.child_frame_id = child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
        q = scene.quaternion(*rpy)
        t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w = q
        return t

    def publish_state(self):
        bad = self.bad_input and self.count % 3 == 1
        for name, (_, frame, tip_world, _, _) in scene.TOOLS.items():
            p = PoseStamped()
            p.header.stamp = rospy.Time.now()
            p.header.frame_id = frame
            x, y, z = self.tips[name]
            p.pose.position.x, p.pose.position.y, p.pose.position.z = (float('nan'), y, z) if bad else (x, y, z)
            p.pose.orientation.w = 1.0
            self.pose_pubs[name].publish(p)
        msg = Float64MultiArray()
        msg.data = scene.DISTANCES[:1] if bad else scene.DISTANCES
        self.dist_pub.publish(msg)

    def publish_images(self):
        stamp = rospy.Time.now()
        for e, eye in enumerate(('left', 'right')):
            info, img = scene.eye_messages(eye, stamp, self.data[e])
            if self.bad_input and self.count % 5 == 2:
                img.data = self.data[e][:100]  # truncated buffer: must be rejected, not crash
            if self.bad_input and self.count % 7 == 3:
                info.K = [0.0] * 9  # uncalibrated: published without overlay, not a crash
            self.info_pubs[e].publish(info)
            self.image_pubs[e].publish(img)

    def run(self):
        r = rospy.Rate(self.rate)
        while not rospy.is_shutdown():
            self.publish_state()  # poses stamped just before the images: drawn at the image stamp
            if self.images:
                self.publish_images()
            self.count += 1
            try:
                r.sleep()
            except rospy.ROSInterruptException:
                break


if __name__ == '__main__':
    rospy.init_node('fake_endoscope')
    FakeEndoscope().run()
