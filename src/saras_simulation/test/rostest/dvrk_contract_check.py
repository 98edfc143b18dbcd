#!/usr/bin/env python3
"""rostest: dvrk_sim messages follow the contract: frame ids, joint names, dVRK convention (tip at
negative z, 10-18 cm below the RCM for PSMs), cartesian pose = FK(joint state) of the same stamp,
CRTK topics at the root identical to the 1.x topics, the master console's MTMs (7 dVRK 1.x joint
names) and head-sensor event, status OK on /diagnostics."""
import sys
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState, Joy

from saras_common import transforms as tfm
from saras_simulation import dvrk_kinematics, dvrk_motion

import diag_status


class ContractTest(unittest.TestCase):
    def test_contract(self):
        cp, js, crtk, status = {}, {}, {}, []
        for arm in ('PSM1', 'PSM2', 'ECM'):
            cp[arm], js[arm], crtk[arm] = {}, {}, {}
            rospy.Subscriber('/dvrk/%s/position_cartesian_current' % arm, PoseStamped,
                             lambda m, a=arm: cp[a].__setitem__(m.header.stamp.to_nsec(), m))
            rospy.Subscriber('/dvrk/%s/state_joint_current' % arm, JointState,
                             lambda m, a=arm: js[a].__setitem__(m.header.stamp.to_nsec(), m))
            rospy.Subscriber('/%s/measured_cp' % arm, PoseStamped,
                             lambda m, a=arm: crtk[a].__setitem__(m.header.stamp.to_nsec(), m))
        mtm, head = {}, []
        for arm in ('MTML', 'MTMR'):
            rospy.Subscriber('/dvrk/%s/state_joint_current' % arm, JointState,
                             lambda m, a=arm: mtm.__setitem__(a, m))
        rospy.Subscriber('/dvrk/footpedals/operatorpresent', Joy, head.append)
        diag_status.subscribe(status)
        rospy.sleep(3.0)
        kin = dvrk_motion.load_kinematics()
        for arm in ('PSM1', 'PSM2', 'ECM'):
            names = dvrk_motion.ECM_JOINT_NAMES if arm == 'ECM' else dvrk_motion.PSM_JOINT_NAMES
            common = set(cp[arm]) & set(js[arm])
            self.assertGreater(len(common), 100, arm)
            for k in sorted(common):
                p, j = cp[arm][k], js[arm][k]
                self.assertEqual(p.header.frame_id, arm)
                self.assertEqual(tuple(j.name), names)
                T = kin.ecm_tip_in_base(j.position) if arm == 'ECM' else kin.psm_tip_in_base(j.position)
                pos = [p.pose.position.x, p.pose.position.y, p.pose.position.z]
                np.testing.assert_allclose(pos, T[:3, 3], atol=1e-9)
                q = p.pose.orientation
                np.testing.assert_allclose(tfm.quaternion_to_matrix([q.x, q.y, q.z, q.w]),
                                           T[:3, :3], atol=1e-9)
                self.assertLess(pos[2], 0.0)
                if arm != 'ECM':
                    self.assertTrue(0.10 <= np.linalg.norm(pos) <= 0.18)
                if k in crtk[arm]:
                    self.assertEqual(crtk[arm][k].pose, p.pose)
            self.assertGreater(len(set(crtk[arm]) & common), 100)
        for arm in ('MTML', 'MTMR'):
            self.assertEqual(tuple(mtm[arm].name), dvrk_kinematics.MTM_JOINT_NAMES)
        self.assertEqual(list(head[-1].buttons), [1])
        mine = [s for s in status if s.component.endswith('dvrk_sim')]
        self.assertTrue(mine and mine[-1].level == diag_status.OK)


if __name__ == '__main__':
    rospy.init_node('dvrk_contract_check')
    rostest.rosrun('saras_simulation', 'dvrk_contract', ContractTest, sys.argv)
