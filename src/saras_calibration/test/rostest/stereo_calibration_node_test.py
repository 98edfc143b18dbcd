#!/usr/bin/env python3
"""rostest: stereo_calibration node on synthetic stereo checkerboard images."""
import os
import shutil
import unittest

import numpy as np
import rospy
import rostest
import yaml
from cv_bridge import CvBridge
from sensor_msgs.msg import Image

from saras_calibration.synthetic import checkerboard_views, render_checkerboard
from saras_common.transforms import make_transform
from saras_calibration.world_frames import entry_transform, load_world_frames

OUT = None   # ~output_dir of the test node (set in the .test file)
K = np.array([[700.0, 0, 322.0], [0, 705.0, 236.0], [0, 0, 1]])
D = np.array([-0.12, 0.05, 0.001, -0.0005, 0.0])


class StereoCalibrationNodeTest(unittest.TestCase):
    def test_calibration_files(self):
        rng = np.random.default_rng(1)
        views = checkerboard_views(rng, 16, 8, 6, 0.005, distance=(0.05, 0.09), spread=0.01)
        T_rl = make_transform(None, [-0.005, 0.0, 0.0])
        br = CvBridge()
        pairs = [(br.cv2_to_imgmsg(render_checkerboard(K, D, (640, 480), T, 8, 6, 0.005), 'mono8'),
                  br.cv2_to_imgmsg(render_checkerboard(K, D, (640, 480), T_rl @ T, 8, 6, 0.005), 'mono8'))
                 for T in views]
        pl = rospy.Publisher('/test/left/image_raw', Image, queue_size=2)
        pr = rospy.Publisher('/test/right/image_raw', Image, queue_size=2)
        # An undecodable image first: the node must survive it.
        junk = Image(height=480, width=640, encoding='bogus', step=640, data=b'\0' * 10)
        report = os.path.join(OUT, 'stereo_report.yaml')
        deadline = rospy.Time.now() + rospy.Duration(90)
        i = 0
        while not os.path.exists(report) and rospy.Time.now() < deadline and not rospy.is_shutdown():
            stamp = rospy.Time.now()
            if i == 0:
                junk.header.stamp = stamp
                pl.publish(junk)
                pr.publish(junk)
            else:
                l, r = pairs[i % len(pairs)]
                l.header.stamp = r.header.stamp = stamp
                pl.publish(l)
                pr.publish(r)
            i += 1
            rospy.sleep(0.1)
        rospy.sleep(0.5)
        self.assertTrue(os.path.exists(report), 'no report written')
        rep = yaml.safe_load(open(report))
        self.assertGreaterEqual(rep["views"], 8)
        self.assertLess(rep['reprojection_rms_px']['left'], 0.5)
        self.assertLess(rep['epipolar_rms_px'], 0.5)
        self.assertAlmostEqual(rep['baseline_m'], 0.005, delta=1e-4)
        left = yaml.safe_load(open(os.path.join(OUT, 'endoscope_left.yaml')))
        Kl = np.reshape(left['camera_matrix']['data'], (3, 3))
        np.testing.assert_allclose(np.diag(Kl)[:2], np.diag(K)[:2], rtol=0.01)
        self.assertEqual(left['camera_name'], 'endoscope_left')
        ext = load_world_frames(os.path.join(OUT, 'stereo_extrinsics.yaml'))[0]
        self.assertEqual(ext['child'], 'endoscope/right_optical_frame')
        self.assertAlmostEqual(entry_transform(ext)[0, 3], 0.005, delta=1e-4)


if __name__ == '__main__':
    rospy.init_node('stereo_calibration_node_test')
    OUT = rospy.get_param('~output_dir')
    shutil.rmtree(OUT, ignore_errors=True)
    rostest.rosrun('saras_calibration', 'stereo_calibration_node', StereoCalibrationNodeTest)
