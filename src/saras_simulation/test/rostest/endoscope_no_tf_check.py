#!/usr/bin/env python3
"""rostest: endoscope_sim without camera TF -> no images, ERROR status; recovers with TF."""
import sys
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import CameraInfo, Image


import diag_status


class NoTfTest(unittest.TestCase):
    def test_hold_then_recover(self):
        images, status = [], []
        rospy.Subscriber('/endoscope/left/image_raw', Image, images.append)
        diag_status.subscribe(status)
        # wait for the node to come up (its diagnostics), then observe 3 s without TF
        deadline = rospy.Time.now() + rospy.Duration(40.0)
        while not [s for s in status if s.component.endswith('endoscope_sim')] and \
                rospy.Time.now() < deadline:
            rospy.sleep(0.1)
        rospy.sleep(3.0)
        mine = [s for s in status if s.component.endswith('endoscope_sim')]
        self.assertTrue(mine, 'no diagnostics from endoscope_sim')
        self.assertEqual(mine[-1].level, diag_status.ERROR)
        self.assertIn('camera pose', mine[-1].message)
        self.assertGreater(mine[-1].rejected, 10)
        self.assertEqual(images, [])
        # provide the optical frames: images must flow
        br = tf2_ros.StaticTransformBroadcaster()
        msgs = []
        for eye, x in (('left', -0.0025), ('right', 0.0025)):
            m = TransformStamped()
            m.header.stamp = rospy.Time.now()
            m.header.frame_id, m.child_frame_id = 'world', 'endoscope/%s_optical_frame' % eye
            m.transform.translation.x, m.transform.translation.z = x, 0.17
            m.transform.rotation.x = 1.0  # looking down (z optical = -z world)
            msgs.append(m)
        br.sendTransform(msgs)
        img = rospy.wait_for_message('/endoscope/left/image_raw', Image, 20.0)
        self.assertEqual((img.width, img.height), (640, 360))
        info = rospy.wait_for_message('/endoscope/left/camera_info', CameraInfo, 5.0)
        # camera_info scaled from the 1280x720 calibration: fx halves, cx = (639.5 + 0.5) / 2 - 0.5
        self.assertAlmostEqual(info.K[0], 450.0, places=9)
        self.assertAlmostEqual(info.K[2], 319.5, places=9)


if __name__ == '__main__':
    rospy.init_node('endoscope_no_tf_check')
    rostest.rosrun('saras_simulation', 'endoscope_no_tf', NoTfTest, sys.argv)
