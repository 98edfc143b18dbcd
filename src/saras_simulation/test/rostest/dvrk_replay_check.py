#!/usr/bin/env python3
"""rostest: replay of a bag through dvrk_sim reproduces the recorded poses (in order, with the
recorded timing), drops the corrupt (NaN) sample, and computes the ECM pose from its joints."""
import math
import sys
import unittest

import numpy as np
import rosbag
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState

from saras_common import transforms as tfm
from saras_simulation import dvrk_motion


def pose_tuple(p):
    return (p.pose.position.x, p.pose.position.y, p.pose.position.z, p.pose.orientation.x,
            p.pose.orientation.y, p.pose.orientation.z, p.pose.orientation.w)


class ReplayTest(unittest.TestCase):
    def test_replay_reproduces_bag(self):
        bag_path = rospy.get_param('~bag')
        recorded = {'PSM1': [], 'PSM2': []}
        with rosbag.Bag(bag_path) as b:
            for topic, msg, _ in b.read_messages():
                arm = topic.split('/')[2]
                if topic.endswith('position_cartesian_current'):
                    recorded[arm].append(pose_tuple(msg))
        got = {'PSM1': [], 'PSM2': [], 'ECM': [], 'ECM_js': {}}

        def on_cp(msg, arm):
            got[arm].append((msg.header.stamp.to_sec(), msg.header.frame_id, pose_tuple(msg),
                             msg.header.stamp.to_nsec()))

        def on_js(msg):
            got['ECM_js'].setdefault(msg.header.stamp.to_nsec(), []).append(list(msg.position))
        subs = [rospy.Subscriber('/dvrk/%s/position_cartesian_current' % a, PoseStamped, on_cp, a)
                for a in ('PSM1', 'PSM2', 'ECM')]
        subs.append(rospy.Subscriber('/dvrk/ECM/state_joint_current', JointState, on_js))
        deadline = rospy.Time.now() + rospy.Duration(15.0)
        while len(got['PSM2']) < 160 and rospy.Time.now() < deadline and not rospy.is_shutdown():
            rospy.sleep(0.1)
        for arm in ('PSM1', 'PSM2'):
            rx = got[arm][5:]  # skip connection start-up
            self.assertGreater(len(rx), 120, arm)
            idx = []
            for stamp, frame, pose, _ in rx:
                self.assertEqual(frame, arm)
                self.assertTrue(all(math.isfinite(v) for v in pose), 'NaN pose published')
                # exactly one recorded sample (poses are distinct)
                match = [i for i, r in enumerate(recorded[arm]) if np.allclose(r, pose, atol=1e-12, rtol=0)]
                self.assertEqual(len(match), 1, '%s pose not in the bag: %s' % (arm, pose))
                idx.append(match[0])
            steps = np.diff(idx) % 100
            bad = 40 if arm == 'PSM2' else None
            for a, s in zip(idx[:-1], steps):
                if bad is not None and a == bad - 1:
                    self.assertEqual(s, 2)   # the NaN sample 40 was dropped, 41 follows 39
                else:
                    self.assertEqual(s, 1, '%s: sample order broken after %d' % (arm, a))
            dt = np.diff([r[0] for r in rx])
            dt = dt[steps == 1]
            self.assertAlmostEqual(float(np.mean(dt)), 0.02, delta=0.003)   # recorded 50 Hz
        # ECM: joints only in the bag -> cartesian = forward kinematics of the same sample
        kin = dvrk_motion.load_kinematics()
        checked = 0
        for stamp, frame, pose, nsec in got['ECM']:
            qs = got['ECM_js'].get(nsec)   # joint states with exactly this header stamp
            if not qs:
                continue
            R = tfm.quaternion_to_matrix(pose[3:])
            errors = []
            for q in qs:
                T = kin.ecm_tip_in_base(q)
                errors.append(max(np.abs(np.asarray(pose[:3]) - T[:3, 3]).max(),
                                  np.abs(R - T[:3, :3]).max()))
            self.assertLess(min(errors), 1e-9, 'ECM pose at %d ns is not the FK of its joints' % nsec)
            checked += 1
        self.assertGreater(checked, 50)


if __name__ == '__main__':
    rospy.init_node('dvrk_replay_check')
    rostest.rosrun('saras_simulation', 'dvrk_replay', ReplayTest, sys.argv)
