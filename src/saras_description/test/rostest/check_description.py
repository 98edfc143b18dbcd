#!/usr/bin/env python3
"""rostest node: the launched descriptions publish the platform's TF tree as documented."""
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros

from saras_description import config as cfg
from saras_description import kinematics as k
from saras_common.transforms import quaternion_from_matrix

ROBOTS = ('mesa_left', 'mesa_right', 'PSM1', 'PSM2', 'ECM', 'touch_left', 'touch_right')


class DescriptionTf(unittest.TestCase):
    """Checks params and transforms against independent expectations (docs/interfaces.md)."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node('check_description')
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)

    def lookup(self, parent, child):
        t = self.buffer.lookup_transform(parent, child, rospy.Time(0), rospy.Duration(20.0))
        p = t.transform.translation
        q = t.transform.rotation
        return np.array([p.x, p.y, p.z]), np.array([q.x, q.y, q.z, q.w])

    def test_robot_descriptions_loaded(self):
        for robot in ROBOTS:
            text = rospy.get_param('/%s/robot_description' % robot)
            self.assertIn('<robot name="%s">' % robot, text)

    def test_rcms_on_the_trocars(self):
        for side, expected in (('mesa_left', (0.02, 0.13, 0.20)), ('mesa_right', (0.02, -0.13, 0.20))):
            p, _ = self.lookup('world', side + '/rcm')
            np.testing.assert_allclose(p, expected, atol=1e-4)
            # set-up pose of display.launch: 13 cm insertion toward the site (0, 0, 0.10)
            tip, _ = self.lookup('world', side + '/tool_tip')
            d = np.array([0.0, 0.0, 0.10]) - np.array(expected)
            np.testing.assert_allclose(tip, np.array(expected) + 0.13 * d / np.linalg.norm(d), atol=1e-4)

    def test_dvrk_tips_and_cameras(self):
        tip, _ = self.lookup('world', 'PSM1/tool_tip')
        np.testing.assert_allclose(tip, [0.02, -0.02, 0.10], atol=1e-4)
        p, q = self.lookup('ECM/tool_tip', 'endoscope/right_optical_frame')
        he = cfg.load_hand_eye()
        t = he.tip_to_left @ he.left_to_right
        np.testing.assert_allclose(p, t[:3, 3], atol=1e-6)
        self.assertGreater(abs(np.dot(q, quaternion_from_matrix(t[:3, :3]))), 1.0 - 1e-9)

    def test_touch_handles(self):
        p, q = self.lookup('touch_left/base', 'touch_left/handle')
        expected = k.touch_handle_in_base([0.0, 0.35, 0.30, 0.0, 0.0, 0.0])
        np.testing.assert_allclose(p, expected[:3, 3], atol=1e-6)


if __name__ == '__main__':
    rostest.rosrun('saras_description', 'description_tf', DescriptionTf)
