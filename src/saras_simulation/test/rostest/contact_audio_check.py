#!/usr/bin/env python3
"""rostest: contact_sim depth/direction against the tissue model for a tip driven through its
ee_pose topic (base frame from /tf_static)
(in contact, out of contact), depth 0 for a tool without pose; microphone chunk format."""
import sys
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PointStamped, PoseStamped, TransformStamped

from saras_simulation.tissue_surface import TissueSurface
from saras_msgs.msg import AudioChunk, Contact

import diag_status


class ContactAudioTest(unittest.TestCase):
    def setUp(self):
        self.pose_pub = rospy.Publisher('/mesa_left/ee_pose', PoseStamped, queue_size=10)
        self.static = tf2_ros.StaticTransformBroadcaster()
        m = TransformStamped()
        m.header.stamp = rospy.Time.now()
        m.header.frame_id, m.child_frame_id = 'world', 'mesa_left/sbs_world'
        m.transform.translation.y = 0.45
        m.transform.rotation.z, m.transform.rotation.w = -np.sqrt(0.5), np.sqrt(0.5)  # yaw -90 deg
        self.static.sendTransform(m)
        self.surf = TissueSurface.from_config(rospy.get_param('~tissue'))

    def send_tip(self, p):
        """Tool tip at world point p, sent as saras_arms_state does: ee_pose in sbs_world."""
        R_wb = np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], float)   # Rz(-pi/2)
        pb = R_wb.T @ (np.asarray(p, float) - [0.0, 0.45, 0.0])
        m = PoseStamped()
        m.header.stamp = rospy.Time.now()
        m.header.frame_id = 'mesa_left/sbs_world'
        m.pose.position.x, m.pose.position.y, m.pose.position.z = pb
        m.pose.orientation.w = 1.0
        self.pose_pub.publish(m)

    def contact_for(self, p, n=10):
        got = []
        sub = rospy.Subscriber('/mesa_left/contact_truth', Contact, got.append)
        end = rospy.Time.now() + rospy.Duration(1.5)
        while rospy.Time.now() < end:
            self.send_tip(p)
            rospy.sleep(0.02)
        got[:] = []
        end = rospy.Time.now() + rospy.Duration(1.0)
        while rospy.Time.now() < end:
            self.send_tip(p)
            rospy.sleep(0.02)
        sub.unregister()
        self.assertGreater(len(got), n)
        return got[-1]

    def test_contact_values(self):
        x, y = 0.01, 0.02
        h = float(self.surf.height(x, y))
        inside = self.contact_for([x, y, h - 0.004])
        _, nrm, sd = self.surf.closest_point([x, y, h - 0.004])
        self.assertAlmostEqual(inside.depth, -sd, delta=1e-6)
        self.assertGreater(inside.depth, 0.003)
        # direction is expressed in mesa_left/sbs_world (yaw -90 deg about world z)
        d = np.array([inside.direction.x, inside.direction.y, inside.direction.z])
        R_wb = np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], float)   # Rz(-pi/2)
        np.testing.assert_allclose(R_wb @ d, nrm, atol=1e-6)
        outside = self.contact_for([x, y, h + 0.01])
        self.assertEqual(outside.depth, 0.0)
        right = rospy.wait_for_message('/mesa_right/contact_truth', Contact, 5.0)
        self.assertEqual(right.depth, 0.0)
        self.assertGreater(abs(right.direction.z), 0.0)   # never a zero vector
        st = []
        sub = diag_status.subscribe(st)
        rospy.sleep(2.5)
        sub.unregister()
        mine = [s for s in st if s.component.endswith('contact_sim') and s.task == 'tool poses']
        self.assertTrue(mine and mine[-1].level == diag_status.WARN and 'mesa_right' in mine[-1].message)
        self.assertGreater(mine[-1].rejected, 0)

    def test_wrong_pose_type(self):
        """A publisher of another type on a tool's pose topic (rospy refuses the connection: the
        md5sums differ): no crash, depth 0 for that tool, counted; the other tool is unaffected."""
        bad = rospy.Publisher('/mesa_right/ee_pose', PointStamped, queue_size=10)
        x, y = 0.01, 0.02
        h = float(self.surf.height(x, y))
        st = []
        sub = diag_status.subscribe(st)
        right = []
        rsub = rospy.Subscriber('/mesa_right/contact_truth', Contact, right.append)
        end = rospy.Time.now() + rospy.Duration(2.5)
        while rospy.Time.now() < end:
            m = PointStamped()
            m.header.stamp = rospy.Time.now()
            m.header.frame_id = 'mesa_right/sbs_world'
            m.point.z = h - 0.004
            bad.publish(m)
            rospy.sleep(0.02)
        rsub.unregister()
        sub.unregister()
        bad.unregister()
        self.assertGreater(len(right), 30)
        self.assertTrue(all(c.depth == 0.0 for c in right))
        mine = [s for s in st if s.component.endswith('contact_sim') and s.task == 'tool poses']
        self.assertTrue(mine and mine[-1].level == diag_status.WARN and 'mesa_right' in mine[-1].message)
        inside = self.contact_for([x, y, h - 0.004])   # the node still serves the left tool
        self.assertGreater(inside.depth, 0.003)

    def test_audio_chunks(self):
        got = []
        sub = rospy.Subscriber('/audio/mic', AudioChunk, got.append)
        rospy.sleep(1.5)
        sub.unregister()
        self.assertGreater(len(got), 50)
        for a, b in zip(got[:-1], got[1:]):
            self.assertEqual(b.header.seq, a.header.seq + 1)
            self.assertAlmostEqual((b.header.stamp - a.header.stamp).to_sec(), 0.02, delta=1e-6)
        m = got[-1]
        self.assertEqual((m.sample_rate, m.channels, m.encoding, len(m.samples)), (16000, 1, 'S16LE', 320))
        self.assertTrue(m.source in ('synthetic',) or m.source)
        pcm = np.concatenate([np.asarray(g.samples) for g in got])
        self.assertGreater(np.abs(pcm).max(), 500)   # not silence


if __name__ == '__main__':
    rospy.init_node('contact_audio_check')
    rostest.rosrun('saras_simulation', 'contact_audio', ContactAudioTest, sys.argv)
