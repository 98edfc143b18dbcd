#!/usr/bin/env python3
"""tank_exchange.test: one exchange per control cycle while the triggers flow, the timer's otherwise.

The tank's timer runs at 20 Hz; the measured twists of both channels (tank_master's triggers) come at
200 Hz. Before, the exchange went out on timer ticks only (20 Hz here; a late tick on a loaded host
thinned out the 1 kHz stream): now one exchange follows each cycle of the two channels' samples. After
the inputs stop, the timer carries it again at its own rate.
"""
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import TwistStamped
from std_msgs.msg import Float64

NS = '/teleop/tank_master/'
TIMER_RATE = 20.0
INPUT_RATE = 200.0


class TankExchange(unittest.TestCase):
    def setUp(self):
        self.energy = []
        self.lock = threading.Lock()
        rospy.Subscriber(NS + 'energy', Float64, self.on_energy, queue_size=1000, tcp_nodelay=True)
        self.pubs = [rospy.Publisher(NS + side + '/meas_cart_vel', TwistStamped, queue_size=100, tcp_nodelay=True)
                     for side in ('left', 'right')]

    def on_energy(self, _):
        with self.lock:
            self.energy.append(time.monotonic())

    def count(self, t0, t1):
        with self.lock:
            return sum(1 for t in self.energy if t0 <= t < t1)

    def test_exchange_follows_the_inputs(self):
        end = time.monotonic() + 20.0
        while time.monotonic() < end and (self.count(0, 1e12) < 5 or any(p.get_num_connections() == 0
                                                                          for p in self.pubs)):
            time.sleep(0.1)
        self.assertGreater(self.count(0, 1e12), 4, 'no energy from tank_master')
        msg = TwistStamped()
        msg.header.frame_id = 'mesa_left/sbs_world'
        cycles, t0 = 0, time.monotonic()
        while time.monotonic() < t0 + 3.0:
            msg.header.stamp = rospy.Time.now()
            for p in self.pubs:
                p.publish(msg)
            cycles += 1
            time.sleep(1.0 / INPUT_RATE)
        t1 = time.monotonic()
        time.sleep(1.0)         # the triggers count as flowing for 10 periods (0.5 s here)
        t2 = time.monotonic()
        time.sleep(2.0)
        t3 = time.monotonic()
        flowing = self.count(t0 + 0.5, t1) / (t1 - t0 - 0.5)
        stopped = self.count(t2, t3) / (t3 - t2)
        sent = cycles / (t1 - t0)
        rospy.loginfo('cycles sent %.1f Hz; energy while they flow %.1f Hz, after %.1f Hz' % (sent, flowing, stopped))
        # a cycle in, an exchange out (this node's own sending and receiving lag on a loaded host)
        self.assertGreater(flowing, 4.0 * TIMER_RATE)
        self.assertGreater(flowing, 0.6 * sent)
        self.assertLess(flowing, 1.2 * sent)
        self.assertGreater(stopped, 0.5 * TIMER_RATE)
        self.assertLess(stopped, 1.2 * TIMER_RATE)


if __name__ == '__main__':
    rospy.init_node('tank_exchange')
    rostest.rosrun('saras_teleop', 'tank_exchange', TankExchange)
