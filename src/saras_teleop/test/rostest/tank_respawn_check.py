#!/usr/bin/env python3
"""tank_respawn.test: the tank's energy before a SIGKILL and after its respawn."""
import os
import signal
import time
import unittest

import rospy
import rostest
from std_msgs.msg import Float32, Float64

from node_util import node_pid, wait_until

NODE = '/teleop/tank_slave/tank_slave'


class TankRespawn(unittest.TestCase):
    def setUp(self):
        self.samples = []
        rospy.Subscriber('/teleop/tank_slave/energy', Float64,
                         lambda m: self.samples.append((time.monotonic(), m.data)), queue_size=100)
        # the peer asks for energy: above T_ava the tank sends P_const away, so its energy falls
        ereq = rospy.Publisher('/teleop/tank_slave/ext_ereq', Float32, queue_size=1)
        self.timer = rospy.Timer(rospy.Duration(0.02), lambda _: ereq.publish(Float32(1.0)))

    def test_respawn_keeps_the_energy_it_had(self):
        self.assertTrue(wait_until(lambda: len(self.samples) > 200, 20.0), 'no energy from tank_slave')
        time.sleep(1.5)             # P_const (2 W) leaves: the energy is below T_init by now
        pid = node_pid(NODE)
        os.kill(pid, signal.SIGKILL)
        t_kill = time.monotonic()
        before = [e for t, e in self.samples if t < t_kill]
        last = before[-1]
        self.assertLess(last, 15.0 - 0.5, 'the energy did not change before the kill: test cannot tell')
        self.assertTrue(wait_until(lambda: any(t > t_kill + 0.5 for t, _ in self.samples), 20.0),
                        'tank_slave not respawned')
        self.assertNotEqual(pid, node_pid(NODE))
        first = next(e for t, e in self.samples if t > t_kill + 0.5)
        self.assertLessEqual(first, last + 1e-9, 'respawned with more energy (%.6f > %.6f J)' % (first, last))
        self.assertGreater(first, 1.0 + 0.5 * (last - 1.0), 'respawned nearly empty (%.3f J of %.3f J)'
                           % (first, last))


if __name__ == '__main__':
    rospy.init_node('tank_respawn')
    rostest.rosrun('saras_teleop', 'tank_respawn', TankRespawn)
