#!/usr/bin/env python3
"""rostest: global_frame_registration node end to end (touches by prompt, endoscope view)."""
import os
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import String
from std_srvs.srv import Trigger

from saras_calibration.pattern import CircularPattern
from saras_common.transforms import (inverse, quaternion_from_transform, rotation_angle_deg,
                                     transform_from_rpy, transform_points)
from saras_calibration.world_frames import entry_transform, load_world_frames

OUT = None   # ~output_file of the test node (set in the .test file)
T_WP = transform_from_rpy([0.05, 0.0, 0.07], [np.pi, 0.0, 0.2])
TRUTH = {'PSM1': transform_from_rpy([0.10, -0.08, 0.22], [0.0, 0.0, 0.0]),
         'mesa_left/sbs_world': transform_from_rpy([0.0, 0.45, 0.0], [0.0, 0.0, -np.pi / 2]),
         'ECM': transform_from_rpy([0.14, 0.0, 0.24], [0.0, 0.0, 0.0])}
X = transform_from_rpy([-0.0025, 0.0, 0.0], [0.0, np.radians(30), 0.0])   # test/data/hand_eye_test.yaml


def pose_msg(T, frame):
    m = PoseStamped()
    m.header.stamp = rospy.Time.now()
    m.header.frame_id = frame
    m.pose.position.x, m.pose.position.y, m.pose.position.z = T[:3, 3]
    q = quaternion_from_transform(T)
    m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w = q
    return m


class GlobalRegistrationNodeTest(unittest.TestCase):
    def setUp(self):
        self.prompt = None
        rospy.Subscriber('/global_frame_registration/prompt', String, self.on_prompt)
        self.pubs = {b: rospy.Publisher(t, PoseStamped, queue_size=1) for b, t in
                     (('PSM1', '/test/PSM1/tip'), ('mesa_left/sbs_world', '/test/mesa_left/tip'),
                      ('ECM', '/test/ECM/tip'), ('pattern', '/test/pattern_pose'))}
        ns = '/global_frame_registration/'
        self.srv = {}
        for s in ('record', 'skip', 'record_endoscope', 'compute', 'save'):
            rospy.wait_for_service(ns + s, timeout=30)
            self.srv[s] = rospy.ServiceProxy(ns + s, Trigger)
        for p in self.pubs.values():
            while p.get_num_connections() == 0:
                rospy.sleep(0.05)

    def on_prompt(self, msg):
        self.prompt = msg.data

    def send(self, key, T, frame):
        for _ in range(2):
            self.pubs[key].publish(pose_msg(T, frame))
            rospy.sleep(0.03)

    def test_procedure(self):
        if os.path.exists(OUT):
            os.remove(OUT)
        rng = np.random.default_rng(3)
        dots = transform_points(T_WP, CircularPattern().dot_positions())
        self.assertFalse(self.srv['record'].call().success)       # no pose yet
        self.assertFalse(self.srv['compute'].call().success)      # nothing recorded
        for base in ('PSM1', 'mesa_left/sbs_world'):
            for k, p in enumerate(transform_points(inverse(TRUTH[base]), dots)):
                deadline = rospy.Time.now() + rospy.Duration(5)
                while (self.prompt is None or 'dot %d with the tool tip of %s' % (k, base) not in self.prompt) \
                        and rospy.Time.now() < deadline:
                    rospy.sleep(0.02)
                self.assertIn('dot %d with the tool tip of %s' % (k, base), self.prompt)
                T = transform_from_rpy(p + rng.normal(0, 0.0002, 3), [np.pi, 0.1, 0.0])
                if k == 2 and base == 'PSM1':   # a pose in the wrong frame is refused
                    self.send(base, T, 'ECM')
                self.send(base, T, base)
                r = self.srv['record'].call()
                self.assertTrue(r.success, r.message)
        # Endoscope: ECM tip straight down 4 cm below the RCM; exact pattern pose in the camera.
        T_be = transform_from_rpy([0.0, 0.0, -0.04], [np.pi, 0.0, 0.0])
        T_cp = inverse(T_be @ X) @ inverse(TRUTH['ECM']) @ T_WP
        self.send('ECM', T_be, 'ECM')
        self.send('pattern', T_cp, 'endoscope/left_optical_frame')
        r = self.srv['record_endoscope'].call()
        self.assertTrue(r.success, r.message)
        r = self.srv['compute'].call()
        self.assertTrue(r.success, r.message)
        self.assertNotIn('NOT registered', r.message)
        self.assertTrue(self.srv['save'].call().success)
        cal = {e['child']: entry_transform(e) for e in load_world_frames(OUT)}
        # Error where it matters: a point of the surgical site (the pattern area) expressed in the
        # base with the true transform and mapped back with the calibrated one.
        site = np.vstack([dots, T_WP[:3, 3]])
        for base, T in TRUTH.items():
            err = np.linalg.norm(transform_points(cal[base] @ inverse(T), site) - site, axis=1)
            self.assertLess(err.max(), 0.0005 if base != 'ECM' else 1e-5, base)
            self.assertLess(rotation_angle_deg(cal[base][:3, :3].T @ T[:3, :3]), 0.3, base)
        # Published on /tf_static.
        buf = tf2_ros.Buffer()
        tf2_ros.TransformListener(buf)
        ts = buf.lookup_transform('world', 'mesa_left/sbs_world', rospy.Time(0), rospy.Duration(5))
        self.assertAlmostEqual(ts.transform.translation.y, 0.45, delta=0.0005)


if __name__ == '__main__':
    rospy.init_node('global_frame_registration_node_test')
    OUT = rospy.get_param('~output_file')
    rostest.rosrun('saras_calibration', 'global_frame_registration_node', GlobalRegistrationNodeTest)
