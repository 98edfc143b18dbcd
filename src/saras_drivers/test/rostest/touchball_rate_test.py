#!/usr/bin/env python3
"""rostest: console packets in => every touchball topic published once per packet, at 1 kHz for
a 1 kHz stream, with the values sent; the TF stylus frame broadcast; each packet answered with a
command packet carrying the published wrench_cmd.

Two phases, because a Python test node cannot itself consume 9 topics x 1 kHz on a 2-core host
without starving (and, through TCP back-pressure, throttling) the receiver under test:
1. 200 Hz for 1 s, all 9 streams subscribed (rospy.AnyMsg): exactly one message per packet.
2. 1 kHz for 3 s, left/state (typed) and right/pose subscribed: publish rate from the header
   stamps (independent of this node's own receive lag), one message per packet, values.
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
ALL = ['/touchball/%s/%s' % (s, t) for s in ('left', 'right')
       for t in ('pose', 'state', 'twist', 'buttons')] + ['/tf']


class Counter(object):
    def __init__(self):
        self.n = 0
        self.lock = threading.Lock()

    def __call__(self, _msg):
        with self.lock:
            self.n += 1


def settle(values, timeout=15.0):
    """Wait until the callable's value stops changing (this node may lag on a loaded host)."""
    end = time.monotonic() + timeout
    prev = None
    while time.monotonic() < end:
        time.sleep(0.5)
        cur = values()
        if cur == prev:
            return cur
        prev = cur
    return prev


class TestRate(unittest.TestCase):
    def setUp(self):
        self.port = rospy.get_param('~port')
        self.cmd_port = rospy.get_param('~command_port')
        self.status = []
        self.status_sub = rospy.Subscriber('/touchball/status', ComponentStatus, self.status.append,
                                           queue_size=100)

    def test_1_every_topic_once_per_packet(self):
        counters = dict((t, Counter()) for t in ALL)
        subs = [rospy.Subscriber(t, rospy.AnyMsg, c, queue_size=10000, tcp_nodelay=True)
                for t, c in counters.items()]
        console = FakeConsole(self.port, self.cmd_port)
        time.sleep(1.5)
        console.stream(200.0, 1.0)
        counts = settle(lambda: (self.status[-1].received, tuple(c.n for c in counters.values())))
        accepted = counts[0]
        self.assertGreaterEqual(accepted, 0.99 * console.seq)
        for t, c in counters.items():
            # + one stale=true state per side when the watchdog fires after the stream
            self.assertEqual(c.n, accepted + (1 if t.endswith('state') else 0), t)
        for s in subs:
            s.unregister()
        console.close()

    def test_2_1khz_in_1khz_out(self):
        states = []
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, states.append, queue_size=10000,
                         tcp_nodelay=True)
        poses = Counter()
        rospy.Subscriber('/touchball/right/pose', rospy.AnyMsg, poses, queue_size=10000, tcp_nodelay=True)
        wrench_pub = rospy.Publisher('/touchball/left/wrench_cmd', WrenchStamped, queue_size=1)
        console = FakeConsole(self.port, self.cmd_port)
        time.sleep(1.5)
        received0 = self.status[-1].received
        console.stream(RATE, 0.3)                          # warm-up (link valid again)
        w = WrenchStamped()
        w.header.frame_id = 'touch_left/base'
        w.wrench.force.x, w.wrench.force.z = 1.0, -2.0
        wrench_pub.publish(w)
        console.stream(RATE, 0.05, t0=0.3)
        sent_before = console.seq
        t0 = time.monotonic()
        t_last = console.stream(RATE, DURATION, t0=10.0)
        send_rate = (console.seq - sent_before) / (t_last - t0)
        rospy.loginfo('send rate %.1f Hz' % send_rate)
        self.assertGreater(send_rate, 0.95 * RATE)
        settle(lambda: (self.status[-1].received, len(states), poses.n))
        accepted = self.status[-1].received - received0
        self.assertEqual(self.status[-1].rejected, 0)
        self.assertGreaterEqual(accepted, 0.99 * console.seq)   # UDP may drop a few when loaded
        self.assertEqual(poses.n, accepted)
        fresh = [m for m in states if not m.stale]
        self.assertEqual(len(fresh), accepted)
        self.assertTrue(states[-1].stale)                  # watchdog after the stream stopped
        stamps = [m.header.stamp.to_sec() for m in fresh if m.sender_time >= console.epoch + 10.0]
        r = (len(stamps) - 1) / (stamps[-1] - stamps[0])
        gaps = sorted(b - a for a, b in zip(stamps, stamps[1:]))
        rospy.loginfo('publish rate %.1f Hz, interval p50 %.2f ms p99 %.2f ms max %.2f ms'
                      % (r, 1e3 * gaps[len(gaps) // 2], 1e3 * gaps[int(0.99 * len(gaps))], 1e3 * gaps[-1]))
        self.assertGreater(r, 0.95 * RATE)
        self.assertLess(r, 1.05 * RATE)
        # the last published state equals the packet it came from, field by field
        last = fresh[-1]
        sent = console.sent[last.packet_seq][0]
        p = last.pose.position
        self.assertEqual((p.x, p.y, p.z), sent.position)
        self.assertAlmostEqual(last.clip_angle, sent.clip_angle, places=12)
        self.assertEqual(last.clutch, sent.clutch)
        self.assertEqual(last.header.frame_id, 'touch_left/base')
        # the device rotates about z at 0.5 rad/s (sender time): the twist estimate sees it
        self.assertAlmostEqual(last.twist.angular.z, 0.5, delta=0.02)
        # one command per accepted packet; the wrench came back on the left device only
        self.assertEqual(len(console.commands), accepted)
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
