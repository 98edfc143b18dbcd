#!/usr/bin/env python3
"""rostest: headless stereo calibration of the simulated endoscope (saras_simulation endoscope_sim).

Moves the endoscope over the simulator's checkerboard (world: centre (0, 0.02, 0.085), face up,
8x6 inner corners, 8 mm) by broadcasting TF world -> endoscope/{left,right}_optical_frame, then
checks the calibration written by stereo_calibration against the simulator's camera_info.
"""
import os
import shutil
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
import yaml
from sensor_msgs.msg import CameraInfo

from saras_common.transforms import make_transform, transform_from_rpy, transform_stamped

OUT = None   # ~output_dir of the test node (set in the .test file)
BOARD_CENTRE = np.array([0.0, 0.02, 0.085]) + transform_from_rpy([0, 0, 0], [np.pi, 0, 0.3])[:3, :3] @ [0.028, 0.020, 0.0]


def camera_pose(rng):
    """Optical frame (z forward) looking at the board from 10-13 cm with up to 30 deg tilt."""
    tilt = transform_from_rpy([0, 0, 0], [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.6, 0.6)])
    look_down = transform_from_rpy([0, 0, 0], [np.pi, 0, 0])       # z down onto the table
    R = (tilt @ look_down)[:3, :3]
    # the board across the image (the node refuses a set without horizontal and vertical coverage)
    target = BOARD_CENTRE + np.array([rng.uniform(-0.02, 0.02), rng.uniform(-0.012, 0.012), 0.0])
    return make_transform(R, target - R[:, 2] * rng.uniform(0.10, 0.13))


class EndoscopeSimStereoTest(unittest.TestCase):
    def test_calibration_matches_simulator(self):
        info = None
        br = tf2_ros.TransformBroadcaster()
        rng = np.random.default_rng(5)
        T_left_right = make_transform(None, [0.005, 0.0, 0.0])
        report = os.path.join(OUT, 'stereo_report.yaml')
        deadline = rospy.Time.now() + rospy.Duration(170)
        pose, switch = camera_pose(rng), rospy.Time.now() + rospy.Duration(1.0)
        while not os.path.exists(report) and rospy.Time.now() < deadline and not rospy.is_shutdown():
            now = rospy.Time.now()
            if now > switch:
                pose, switch = camera_pose(rng), now + rospy.Duration(1.0)
            br.sendTransform([transform_stamped('world', 'endoscope/left_optical_frame', pose, now),
                              transform_stamped('world', 'endoscope/right_optical_frame', pose @ T_left_right, now)])
            if info is None:
                try:
                    info = rospy.wait_for_message('/endoscope/left/camera_info', CameraInfo, timeout=0.05)
                except rospy.ROSException:
                    pass
            rospy.sleep(0.05)
        rospy.sleep(0.5)
        self.assertIsNotNone(info, 'no camera_info from the simulator')
        self.assertTrue(os.path.exists(report), 'stereo_calibration wrote no report')
        rep = yaml.safe_load(open(report))
        left = yaml.safe_load(open(os.path.join(OUT, 'endoscope_left.yaml')))
        K_sim = np.reshape(info.K, (3, 3))
        K_cal = np.reshape(left['camera_matrix']['data'], (3, 3))
        rospy.loginfo('simulator K %s, calibrated K %s, report %s', K_sim.tolist(), K_cal.tolist(), rep)
        np.testing.assert_allclose(np.diag(K_cal)[:2], np.diag(K_sim)[:2], rtol=0.01)
        np.testing.assert_allclose(K_cal[:2, 2], K_sim[:2, 2], atol=3.0)
        self.assertAlmostEqual(rep['baseline_m'], 0.005, delta=0.0002)
        self.assertLess(rep['reprojection_rms_px']['left'], 1.0)
        self.assertLess(rep['epipolar_rms_px'], 1.0)


if __name__ == '__main__':
    rospy.init_node('endoscope_sim_stereo_test')
    OUT = rospy.get_param('~output_dir')
    shutil.rmtree(OUT, ignore_errors=True)
    rostest.rosrun('saras_calibration', 'endoscope_sim_stereo', EndoscopeSimStereoTest)
