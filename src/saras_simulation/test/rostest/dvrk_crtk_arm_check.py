#!/usr/bin/env python3
"""rostest: the CRTK arm sequence of the dVRK's arm test (enable, home, move_jp, servo_jp,
prepare for cartesian, move_cp, servo_cp, jaw open/close) on /PSM1, /ECM and /MTMR, with the
client's message types (crtk_msgs/StringStamped, OperatingState, sensor_msgs/JointState,
geometry_msgs/PoseStamped) and its busy semantics (a move answers busy, then idle); every goal
must be reached. Then the arm, left alone, returns to the scripted motion."""
import math
import sys
import threading
import unittest

import numpy as np
import rospy
import rostest
from crtk_msgs.msg import OperatingState, StringStamped
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState

from saras_simulation.dvrk_ros_arm import fill_pose, pose_to_matrix


class Arm(object):
    """Minimal CRTK client of one arm (topics as crtk_python_client uses them)."""

    def __init__(self, name):
        self.name = name
        self.cond = threading.Condition()
        self.states, self.js, self.cp, self.sp_cp, self.jaw = [], None, None, None, None
        ns = '/%s/' % name
        rospy.Subscriber(ns + 'operating_state', OperatingState, self._state)
        rospy.Subscriber(ns + 'measured_js', JointState, lambda m: self._set('js', m))
        rospy.Subscriber(ns + 'measured_cp', PoseStamped, lambda m: self._set('cp', m))
        rospy.Subscriber(ns + 'setpoint_cp', PoseStamped, lambda m: self._set('sp_cp', m))
        rospy.Subscriber(ns + 'jaw/measured_js', JointState, lambda m: self._set('jaw', m))
        self.pub = {n: rospy.Publisher(ns + n, t, queue_size=10, latch=(n == 'state_command'))
                    for n, t in (('state_command', StringStamped), ('move_jp', JointState),
                                 ('servo_jp', JointState), ('move_cp', PoseStamped),
                                 ('servo_cp', PoseStamped), ('jaw/move_jp', JointState))}

    def _state(self, m):
        with self.cond:
            self.states.append((rospy.Time.now(), m))
            self.cond.notify_all()

    def _set(self, k, m):
        setattr(self, k, m)

    def wait_state(self, since, pred, timeout=10.0):
        end = rospy.Time.now() + rospy.Duration(timeout)
        with self.cond:
            while not rospy.is_shutdown() and rospy.Time.now() < end:
                if any(t >= since and pred(m) for t, m in self.states):
                    return True
                self.cond.wait(0.05)
        return False

    def command(self, cmd):
        t = rospy.Time.now()
        m = StringStamped(string=cmd)
        m.header.stamp = t
        self.pub['state_command'].publish(m)
        return t

    def move(self, topic, msg, timeout=30.0):
        """Publish a move, wait for busy then idle (as wait_move_handle.wait())."""
        t = rospy.Time.now()
        msg.header.stamp = t
        self.pub[topic].publish(msg)
        busy = self.wait_state(t, lambda m: m.is_busy, timeout)
        idle = self.wait_state(t, lambda m: not m.is_busy and m.header.stamp >= self._busy_stamp(t),
                               timeout)
        return busy and idle

    def _busy_stamp(self, since):
        with self.cond:
            s = [m.header.stamp for t, m in self.states if t >= since and m.is_busy]
        return s[0] if s else rospy.Time(1e9)

    def jp(self):
        rospy.sleep(0.1)
        return np.array(self.js.position)

    def pose(self):
        rospy.sleep(0.1)
        return pose_to_matrix(self.cp.pose)


def joint_msg(q):
    return JointState(position=list(q))


def pose_msg(T):
    m = PoseStamped()
    fill_pose(m.pose, T)
    return m


class CrtkArmTest(unittest.TestCase):
    def wait_data(self, arm):
        end = rospy.Time.now() + rospy.Duration(20.0)
        while arm.js is None or arm.cp is None:
            self.assertLess(rospy.Time.now(), end, '%s: no measured_js/measured_cp' % arm.name)
            rospy.sleep(0.1)

    def enable_home(self, arm):
        t = arm.command('enable')
        self.assertTrue(arm.wait_state(t, lambda m: m.state == 'ENABLED'), arm.name)
        t = arm.command('home')
        self.assertTrue(arm.wait_state(t, lambda m: m.is_homed and not m.is_busy), arm.name)

    def move_jp(self, arm, goal, tol=1e-4):
        self.assertTrue(arm.move('move_jp', joint_msg(goal)), arm.name)
        np.testing.assert_allclose(arm.jp(), goal, atol=tol, err_msg=arm.name)

    def joint_moves(self, arm):
        q0 = arm.jp()
        self.move_jp(arm, q0)                               # move to the current position
        for s in (1.0, -1.0):
            goal = q0.copy()
            goal[0] += s * math.radians(10.0)
            goal[1] -= s * math.radians(10.0)
            self.move_jp(arm, goal)
        self.move_jp(arm, q0)
        # servo_jp: 2 s of a 5 deg cosine on the first two joints, the arm follows each set-point
        rate = rospy.Rate(100)
        for i in range(200):
            goal = q0.copy()
            goal[:2] += math.radians(5.0) * (1.0 - math.cos(2.0 * math.pi * i / 200.0))
            arm.pub['servo_jp'].publish(joint_msg(goal))
            rate.sleep()
        np.testing.assert_allclose(arm.jp()[:2], goal[:2], atol=1e-3)

    def cartesian(self, arm, start, pos_tol, rot_tol):
        self.move_jp(arm, start)
        T0 = arm.pose()
        for dx, dy in ((-0.05, 0.0), (0.05, 0.0), (0.0, 0.0), (0.0, -0.05), (0.0, 0.05), (0.0, 0.0)):
            goal = T0.copy()
            goal[:3, 3] += (dx, dy, 0.0)
            self.assertTrue(arm.move('move_cp', pose_msg(goal)), '%s move_cp %s' % (arm.name, (dx, dy)))
            T = arm.pose()
            self.assertLess(np.linalg.norm(T[:3, 3] - goal[:3, 3]), pos_tol, (arm.name, dx, dy))
            c = (np.trace(T[:3, :3] @ goal[:3, :3].T) - 1.0) / 2.0
            self.assertLess(math.acos(max(-1.0, min(1.0, c))), rot_tol, arm.name)
        rate = rospy.Rate(100)
        worst, sent = 0.0, []
        for i in range(300):                                # servo_cp: 3 s, 2 cm cosine in x and y
            goal = T0.copy()
            goal[:2, 3] += 0.02 * (1.0 - math.cos(2.0 * math.pi * i / 300.0))
            arm.pub['servo_cp'].publish(pose_msg(goal))
            sent.append(goal[:3, 3])
            rate.sleep()
            if i > 5 and arm.sp_cp is not None:
                # the set-point lies on the commanded path (whatever the latency of a busy host)
                sp = pose_to_matrix(arm.sp_cp.pose)[:3, 3]
                worst = max(worst, min(np.linalg.norm(sp - g) for g in sent[-100:]))
        rospy.sleep(0.2)
        self.assertLess(np.linalg.norm(arm.pose()[:3, 3] - goal[:3, 3]), pos_tol, arm.name)
        self.assertLess(worst, pos_tol, '%s: setpoint_cp %.4f m off the servo_cp path' % (arm.name, worst))

    def test_psm1(self):
        arm = Arm('PSM1')
        self.wait_data(arm)
        self.enable_home(arm)
        self.joint_moves(arm)
        self.cartesian(arm, np.array([0.0, 0.0, 0.12, 0.0, 0.0, 0.0]), 1e-3, 1e-3)
        for angle in (math.radians(60.0), math.radians(-20.0)):  # jaw open, close
            self.assertTrue(arm.move('jaw/move_jp', joint_msg([angle])))
            rospy.sleep(0.1)
            self.assertAlmostEqual(arm.jaw.position[0], angle, places=4)
        # left alone for client_timeout (2 s) + rejoin (2 s): back on the script, moving again
        held = arm.jp()
        rospy.sleep(5.0)
        a, b = arm.jp(), None
        rospy.sleep(0.5)
        b = arm.jp()
        self.assertGreater(np.abs(b - a).max(), 1e-4, 'PSM1 did not return to the scripted motion')
        self.assertGreater(np.abs(a - held).max(), 1e-3)

    def test_ecm_mtm(self):
        ecm, mtm = Arm('ECM'), Arm('MTMR')
        for arm in (ecm, mtm):
            self.wait_data(arm)
            self.enable_home(arm)
        self.joint_moves(mtm)
        self.joint_moves(ecm)
        # 4 joints cannot keep the orientation of a translated goal: the position is reached
        self.cartesian(ecm, np.array([0.0, 0.0, 0.12, 0.0]), 2e-3, 0.5)
        t = ecm.command('disable')
        self.assertTrue(ecm.wait_state(t, lambda m: m.state == 'DISABLED'))
        q = ecm.jp()
        goal = q.copy()
        goal[0] += 0.1
        ecm.pub['move_jp'].publish(joint_msg(goal))   # ignored while disabled
        rospy.sleep(1.0)
        np.testing.assert_allclose(ecm.jp(), q, atol=1e-9)
        t = ecm.command('enable')
        self.assertTrue(ecm.wait_state(t, lambda m: m.state == 'ENABLED'))


if __name__ == '__main__':
    rospy.init_node('dvrk_crtk_arm_check')
    rostest.rosrun('saras_simulation', 'dvrk_crtk_arm', CrtkArmTest, sys.argv)
