#!/usr/bin/env python3
"""rostest: hand_eye_calibration node end to end with synthetic poses."""
import os
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from std_srvs.srv import Trigger

from saras_calibration.synthetic import ecm_hand_eye_dataset
from saras_common.transforms import inverse, quaternion_from_transform, rotation_angle_deg
from saras_calibration.world_frames import entry_transform, load_world_frames
from saras_msgs.srv import RemoveSample

OUT = None   # ~output_file of the test node (set in the .test file)


def pose_msg(T, frame):
    m = PoseStamped()
    m.header.stamp = rospy.Time.now()
    m.header.frame_id = frame
    m.pose.position.x, m.pose.position.y, m.pose.position.z = T[:3, 3]
    q = quaternion_from_transform(T)
    m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w = q
    return m


class HandEyeNodeTest(unittest.TestCase):
    def setUp(self):
        self.ee_pub = rospy.Publisher('/test/ecm_pose', PoseStamped, queue_size=1)
        self.cm_pub = rospy.Publisher('/test/marker_pose', PoseStamped, queue_size=1)
        ns = '/hand_eye_calibration/'
        for s in ('take_sample', 'compute', 'save', 'remove_sample'):
            rospy.wait_for_service(ns + s, timeout=30)
        self.take = rospy.ServiceProxy(ns + 'take_sample', Trigger)
        self.compute = rospy.ServiceProxy(ns + 'compute', Trigger)
        self.save = rospy.ServiceProxy(ns + 'save', Trigger)
        self.remove = rospy.ServiceProxy(ns + 'remove_sample', RemoveSample)
        while self.ee_pub.get_num_connections() == 0 or self.cm_pub.get_num_connections() == 0:
            rospy.sleep(0.05)

    def publish(self, T_be, T_cm):
        for _ in range(3):
            self.ee_pub.publish(pose_msg(T_be, 'ECM'))
            self.cm_pub.publish(pose_msg(T_cm, 'endoscope/left_optical_frame'))
            rospy.sleep(0.03)

    def test_procedure(self):
        if os.path.exists(OUT):
            os.remove(OUT)
        ee, cm, X, out = ecm_hand_eye_dataset(np.random.default_rng(7), 20, outlier_fraction=0.15)
        # No pose yet: refused with a reason.
        r = self.take()
        self.assertFalse(r.success)
        self.assertIn('no valid pose', r.message)
        self.assertFalse(self.compute().success)
        for T_be, T_cm in zip(ee, cm):
            self.publish(T_be, T_cm)
            r = self.take()
            self.assertTrue(r.success, r.message)
        # A NaN pose is rejected by the subscriber: the next sample uses the last valid pose...
        bad = pose_msg(ee[0], 'ECM')
        bad.pose.position.x = float('nan')
        self.ee_pub.publish(bad)
        rospy.sleep(0.1)
        self.assertTrue(self.take().success)
        # ... and that duplicate is removed again by index.
        r = self.remove(-1)
        self.assertTrue(r.success)
        self.assertEqual(r.message, '20 samples')
        self.assertFalse(self.remove(99).success)
        r = self.compute()
        self.assertTrue(r.success, r.message)
        self.assertIn('17/20 inliers', r.message)
        self.assertTrue(self.save().success)
        entries = load_world_frames(OUT)
        he = [e for e in entries if e['child'] == 'endoscope/left_optical_frame'][0]
        self.assertEqual(he['parent'], 'ECM/tool_tip')
        # The template's stereo entry is kept.
        self.assertTrue(any(e['child'] == 'endoscope/right_optical_frame' for e in entries))
        T = entry_transform(he)
        E = inverse(X) @ T
        self.assertLess(rotation_angle_deg(E[:3, :3]), 0.2)
        self.assertLess(np.linalg.norm(T[:3, 3] - X[:3, 3]), 0.001)


if __name__ == '__main__':
    rospy.init_node('hand_eye_node_test')
    OUT = rospy.get_param('~output_file')
    rostest.rosrun('saras_calibration', 'hand_eye_node', HandEyeNodeTest)
