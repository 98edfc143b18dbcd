#!/usr/bin/env python3
"""rostest: pattern_pose_detector publishes the pattern pose of a rendered image; blank and
undecodable images publish nothing and do not kill the node."""
import unittest

import numpy as np
import rospy
import rostest
from cv_bridge import CvBridge
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import CameraInfo, Image

from saras_calibration.pattern import CircularPattern
from saras_common.transforms import inverse, pose_to_matrix, rotation_angle_deg, transform_from_rpy

K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])


class PatternPoseDetectorTest(unittest.TestCase):
    def test_detection(self):
        poses = []
        rospy.Subscriber('/test_cam/pattern_pose', PoseStamped, poses.append)
        pi = rospy.Publisher('/test_cam/camera_info', CameraInfo, queue_size=1, latch=True)
        pim = rospy.Publisher('/test_cam/image', Image, queue_size=1)
        info = CameraInfo(width=640, height=480, K=list(K.ravel()), D=[0.0] * 5, distortion_model='plumb_bob')
        info.header.frame_id = 'cam'
        pi.publish(info)
        while pim.get_num_connections() == 0:
            rospy.sleep(0.05)
        T = transform_from_rpy([0.01, -0.005, 0.30], [0.2, 0.1, 0.3])
        br = CvBridge()
        good = br.cv2_to_imgmsg(CircularPattern().render(K, (640, 480), T), 'mono8')
        blank = br.cv2_to_imgmsg(np.full((480, 640), 128, np.uint8), 'mono8')
        junk = Image(height=480, width=640, encoding='bogus', step=640, data=b'\0' * 10)
        for msg in (junk, blank):
            for _ in range(3):
                msg.header.stamp = rospy.Time.now()
                pim.publish(msg)
                rospy.sleep(0.1)
        self.assertEqual(poses, [])
        deadline = rospy.Time.now() + rospy.Duration(20)
        while not poses and rospy.Time.now() < deadline:
            good.header.stamp = rospy.Time.now()
            good.header.frame_id = 'cam'
            pim.publish(good)
            rospy.sleep(0.1)
        self.assertTrue(poses, 'no pattern pose published')
        self.assertEqual(poses[-1].header.frame_id, 'cam')
        E = inverse(T) @ pose_to_matrix(poses[-1].pose)
        self.assertLess(rotation_angle_deg(E[:3, :3]), 0.3)
        self.assertLess(np.linalg.norm(E[:3, 3]), 0.001)


if __name__ == '__main__':
    rospy.init_node('pattern_pose_detector_node_test')
    rostest.rosrun('saras_calibration', 'pattern_pose_detector_node', PatternPoseDetectorTest)
