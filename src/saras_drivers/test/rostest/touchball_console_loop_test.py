#!/usr/bin/env python3
"""rostest (touchball_console_sim + touchball_receiver over real UDP): a force published on
wrench_cmd travels back to the simulated console and moves the hand+device model by F/k
(static deflection of the hand spring), on the commanded device only; when the commands stop,
the device returns (console-side command timeout)."""
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import WrenchStamped

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


if __name__ == '__main__':
    rospy.init_node('touchball_console_loop_test')
    rostest.rosrun('saras_drivers', 'touchball_console_loop', TestLoop, sys.argv)
