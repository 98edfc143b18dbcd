#!/usr/bin/env python3
"""rostest (touchball_console_sim + touchball_receiver over real UDP): a force published on
wrench_cmd travels back to the simulated console and moves the hand+device model by F/k
(static deflection of the hand spring), on the commanded device only; when the commands stop,
the device returns (console-side command timeout). Also: touch_<side>/joint_states (the receiver's Touch IK)
reproduce the stylus pose through saras_description's forward kinematics."""
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import WrenchStamped
from sensor_msgs.msg import JointState

from saras_description import kinematics
from saras_simulation.saras_arm_model import quat_to_matrix

from saras_msgs.msg import HapticDeviceState

K_HAND = 300.0      # [N/m] hand_stiffness in the .test file
FORCE = 2.0         # [N]


class TestLoop(unittest.TestCase):
    def test_force_moves_device(self):
        lock = threading.Lock()
        z = {'left': [], 'right': []}

        def on_state(msg):
            if not msg.stale:
                with lock:
                    z[msg.device].append((time.monotonic(), msg.pose.position.z))
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, on_state, queue_size=5000)
        rospy.Subscriber('/touchball/right/state', HapticDeviceState, on_state, queue_size=5000)
        pub = rospy.Publisher('/touchball/left/wrench_cmd', WrenchStamped, queue_size=10)
        joints, poses = [], {}

        def on_state_pose(msg):
            if msg.device == 'left' and not msg.stale:
                with lock:
                    poses[msg.header.stamp.to_nsec()] = msg.pose
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, on_state_pose, queue_size=5000)
        rospy.Subscriber('/touch_left/joint_states', JointState, joints.append, queue_size=100)

        def mean_z(side, t0, t1):
            with lock:
                v = [p for t, p in z[side] if t0 <= t <= t1]
            self.assertGreater(len(v), 50, side)
            return float(np.mean(v))

        end = time.monotonic() + 20.0
        while time.monotonic() < end and len(z['left']) < 500:
            time.sleep(0.1)
        t0 = time.monotonic()
        time.sleep(0.5)
        base_l, base_r = mean_z('left', t0, time.monotonic()), mean_z('right', t0, time.monotonic())
        w = WrenchStamped()
        w.header.frame_id = 'touch_left/base'
        w.wrench.force.z = FORCE
        t_push = time.monotonic()
        while time.monotonic() - t_push < 2.5:
            w.header.stamp = rospy.Time.now()
            pub.publish(w)
            time.sleep(0.005)
        t1 = time.monotonic()
        pushed_l = mean_z('left', t1 - 0.5, t1)
        pushed_r = mean_z('right', t1 - 0.5, t1)
        rospy.loginfo('left z %.5f -> %.5f m (expected +%.5f), right %.5f -> %.5f'
                      % (base_l, pushed_l, FORCE / K_HAND, base_r, pushed_r))
        self.assertAlmostEqual(pushed_l - base_l, FORCE / K_HAND, delta=0.1 * FORCE / K_HAND)
        self.assertAlmostEqual(pushed_r, base_r, delta=1e-6)
        time.sleep(1.5)                                    # commands stopped: force times out
        t2 = time.monotonic()
        self.assertAlmostEqual(mean_z('left', t2 - 0.5, t2), base_l, delta=0.05 * FORCE / K_HAND)
        # joint_states (published with the stamp of the packet they come from) => FK = stylus pose
        self.assertEqual(joints[-1].name[0], 'touch_left/waist')
        checked = 0
        with lock:
            for js in joints[-20:]:
                pose = poses.get(js.header.stamp.to_nsec())
                if pose is None:
                    continue
                t = kinematics.touch_handle_in_base(js.position)
                p = pose.position
                self.assertLess(np.linalg.norm(t[:3, 3] - [p.x, p.y, p.z]), 1e-9)
                o = pose.orientation
                self.assertLess(np.abs(t[:3, :3] - quat_to_matrix((o.x, o.y, o.z, o.w))).max(), 1e-9)
                checked += 1
        self.assertGreater(checked, 5)


if __name__ == '__main__':
    rospy.init_node('touchball_console_loop_test')
    rostest.rosrun('saras_simulation', 'touchball_console_loop', TestLoop, sys.argv)
