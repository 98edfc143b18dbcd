#!/usr/bin/env python3
"""rostest: projection truth of endoscope_sim and left/right camera_info consistency.

The checkerboard corners (3D, from the node's own target parameters, in world) are projected with
the *published* camera_info (K, D: raw image) and the TF world -> optical frame at the image
stamp; they must coincide with the corners detected in the published image within 1 px."""
import sys
import unittest

import cv2
import numpy as np
import rospy
import rostest
import tf2_ros
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import String

from saras_common import transforms as tfm


def tf_matrix(ts):
    t, q = ts.transform.translation, ts.transform.rotation
    return tfm.transform_from_quaternion([t.x, t.y, t.z], [q.x, q.y, q.z, q.w])


class TruthTest(unittest.TestCase):
    def test_projection_truth_and_stereo_info(self):
        buf = tf2_ros.Buffer(rospy.Duration(30.0))
        tf2_ros.TransformListener(buf)
        spec = rospy.get_param('/endoscope/endoscope_sim/targets/checkerboard')
        cols, rows, sq = int(spec['cols']), int(spec['rows']), float(spec['square'])
        T_wb = tfm.transform_from_rpy(spec['xyz'], spec['rpy'])
        obj = np.array([(i * sq, j * sq, 0.0) for j in range(rows) for i in range(cols)])
        obj_w = obj @ T_wb[:3, :3].T + T_wb[:3, 3]
        infos = {}
        for eye in ('left', 'right'):
            infos[eye] = rospy.wait_for_message('/endoscope/%s/camera_info' % eye, CameraInfo, 60.0)
        L, R = infos['left'], infos['right']
        self.assertEqual((L.width, L.height), (1280, 720))
        self.assertEqual((L.width, L.height, L.distortion_model), (R.width, R.height, R.distortion_model))
        self.assertEqual(L.header.frame_id, 'endoscope/left_optical_frame')
        self.assertEqual(R.header.frame_id, 'endoscope/right_optical_frame')
        np.testing.assert_allclose(L.K, R.K)
        self.assertEqual(L.P[3], 0.0)
        baseline_info = -R.P[3] / R.P[0]
        T_lr = tf_matrix(buf.lookup_transform('endoscope/left_optical_frame',
                                              'endoscope/right_optical_frame', rospy.Time(0),
                                              rospy.Duration(10.0)))
        # the right camera sits at +x of the left one, at the calibrated baseline (~5 mm)
        self.assertAlmostEqual(T_lr[0, 3], baseline_info, delta=1e-4)
        self.assertAlmostEqual(baseline_info, 0.005, delta=0.002)
        checked = 0
        for eye in ('left', 'right'):
            for _ in range(3):
                img_msg = rospy.wait_for_message('/endoscope/%s/image_raw' % eye, Image, 60.0)
                info = infos[eye]
                self.assertEqual(img_msg.header.frame_id, info.header.frame_id)
                self.assertEqual(img_msg.encoding, 'bgr8')
                img = np.frombuffer(img_msg.data, np.uint8).reshape(img_msg.height, img_msg.width, 3)
                gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
                ok, corners = cv2.findChessboardCorners(gray, (cols, rows))
                self.assertTrue(ok, '%s: checkerboard not found' % eye)
                corners = cv2.cornerSubPix(gray, corners, (7, 7), (-1, -1),
                                           (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-4))
                T_wc = tf_matrix(buf.lookup_transform('world', info.header.frame_id,
                                                      img_msg.header.stamp, rospy.Duration(2.0)))
                T_cw = tfm.inverse(T_wc)
                pc = obj_w @ T_cw[:3, :3].T + T_cw[:3, 3]
                uv, _ = cv2.projectPoints(pc.reshape(-1, 1, 3), np.zeros(3), np.zeros(3),
                                          np.reshape(info.K, (3, 3)), np.asarray(info.D))
                uv = uv.reshape(-1, 2)
                err = np.linalg.norm(uv[:, None] - corners.reshape(1, -1, 2), axis=2).min(axis=1)
                rospy.loginfo('%s: max corner error %.3f px, mean %.3f px', eye, err.max(), err.mean())
                self.assertLess(err.max(), 1.0)
                checked += 1
        self.assertEqual(checked, 6)
        # the target is shown on request only: hide it through ~target
        pub = rospy.Publisher('/endoscope/endoscope_sim/target', String, queue_size=1, latch=True)
        pub.publish(String('none'))
        rospy.sleep(1.0)
        img_msg = rospy.wait_for_message('/endoscope/left/image_raw', Image, 30.0)
        img = np.frombuffer(img_msg.data, np.uint8).reshape(img_msg.height, img_msg.width, 3)
        ok, _ = cv2.findChessboardCorners(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), (cols, rows))
        self.assertFalse(ok)


if __name__ == '__main__':
    rospy.init_node('endoscope_truth_check')
    rostest.rosrun('saras_simulation', 'endoscope_truth', TruthTest, sys.argv)
