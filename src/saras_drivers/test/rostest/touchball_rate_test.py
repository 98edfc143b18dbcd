#!/usr/bin/env python3
"""rostest: 1 kHz of console packets in => every touchball topic published once per packet
(1 kHz), with the values sent, the TF stylus frame broadcast, and each packet answered with a
command packet carrying the published wrench_cmd.

Counting uses rospy.AnyMsg subscribers (no deserialisation) so that the test node, not the
receiver, is not the bottleneck on a loaded machine; the values are checked on a typed topic.
"""
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import WrenchStamped

from saras_drivers import touchball_protocol as tp
from saras_msgs.msg import ComponentStatus, HapticDeviceState
from touchball_fake_console import FakeConsole

RATE = 1000.0
DURATION = 3.0
TOPICS = ['/touchball/%s/%s' % (s, t) for s in ('left', 'right')
          for t in ('pose', 'state', 'twist', 'buttons')] + ['/tf']


class Counter(object):
    def __init__(self):
        self.stamps = []
        self.lock = threading.Lock()

    def __call__(self, _msg):
        with self.lock:
            self.stamps.append(time.monotonic())

    def count_between(self, t0, t1):
        with self.lock:
            return sum(1 for s in self.stamps if t0 <= s <= t1)


class TestRate(unittest.TestCase):
    def test_1khz_in_1khz_out(self):
        port = rospy.get_param('~port')
        cmd_port = rospy.get_param('~command_port')
        counters = dict((t, Counter()) for t in TOPICS)
        for t, c in counters.items():
            rospy.Subscriber(t, rospy.AnyMsg, c, queue_size=10000, tcp_nodelay=True)
        states = []
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, states.append, queue_size=10000)
        status = []
        rospy.Subscriber('/touchball/status', ComponentStatus, status.append, queue_size=100)
        wrench_pub = rospy.Publisher('/touchball/left/wrench_cmd', WrenchStamped, queue_size=1)
        console = FakeConsole(port, cmd_port)
        time.sleep(1.5)                                   # connections
        console.stream(RATE, 0.3)                         # warm-up (link becomes valid)
        w = WrenchStamped()
        w.header.frame_id = 'touch_left/base'
        w.wrench.force.x, w.wrench.force.z = 1.0, -2.0
        wrench_pub.publish(w)
        console.stream(RATE, 0.05, t0=0.3)
        sent_before = console.seq
        t0 = time.monotonic()
        t_last = console.stream(RATE, DURATION, t0=10.0)
        send_rate = (console.seq - sent_before) / (t_last - t0)
        time.sleep(1.0)                                   # let queued messages arrive
        n_window = console.seq - sent_before
        for t, c in counters.items():
            n = c.count_between(t0, time.monotonic())
            rospy.loginfo('%s: %d messages for %d packets' % (t, n, n_window))
            # one message per accepted packet (a few may be lost in the OS on a loaded host)
            self.assertGreaterEqual(n, 0.97 * n_window, t)
            self.assertLessEqual(n, n_window, t)
        rospy.loginfo('send rate %.1f Hz' % send_rate)
        self.assertGreater(send_rate, 0.9 * RATE)
        self.assertEqual(status[-1].rejected, 0)
        self.assertGreaterEqual(status[-1].received, 0.97 * console.seq)
        # the last published state equals the packet it came from, field by field
        last = states[-1]
        sent = console.sent[last.packet_seq][0]
        p = last.pose.position
        self.assertEqual((p.x, p.y, p.z), sent.position)
        self.assertAlmostEqual(last.clip_angle, sent.clip_angle, places=12)
        self.assertEqual(last.clutch, sent.clutch)
        self.assertEqual(last.header.frame_id, 'touch_left/base')
        self.assertFalse(last.stale)
        # the device rotates about z at 0.5 rad/s (sender time): the twist estimate sees it
        self.assertAlmostEqual(last.twist.angular.z, 0.5, delta=0.02)
        # about one command per packet; the wrench came back on the left device only
        n_cmd = sum(1 for t, _ in console.commands if t >= t0)
        self.assertGreaterEqual(n_cmd, 0.97 * n_window)
        cmds = [tp.unpack_command(d) for _, d in console.commands]
        enabled = [c.devices[0] for c in cmds if c.devices[0].enabled]
        self.assertTrue(enabled, 'no enabled force command came back')
        self.assertEqual(enabled[0].force, (1.0, 0.0, -2.0))
        self.assertFalse(any(c.devices[1].enabled for c in cmds))
        # wrench_cmd stopped > wrench_timeout ago: the latest commands carry zero force
        self.assertFalse(cmds[-1].devices[0].enabled)
        console.close()


if __name__ == '__main__':
    rospy.init_node('touchball_rate_test')
    rostest.rosrun('saras_drivers', 'touchball_rate', TestRate, sys.argv)
