#!/usr/bin/env python3
"""rostest: malformed, replayed, reordered and foreign datagrams never reach a topic, never get a
command packet back, and every one is counted on /diagnostics under its reason; bad force
commands are counted there too."""
import random
import struct
import sys
import time
import unittest
import zlib

import rospy
import rostest
from geometry_msgs.msg import PoseStamped, WrenchStamped

from saras_drivers import touchball_protocol as tp
from touchball_fake_console import FakeConsole, LinkDiagnostics


def bad_datagrams(good, sent2):
    """Random, truncated, bit-flipped, wrong-version, NaN, replayed and reordered datagrams, built
    from the accepted packets `good` (sequence 0-4) and the devices sent with sequence 2."""
    rng = random.Random(7)
    bad = []
    for _ in range(300):
        bad.append(bytes(rng.getrandbits(8) for _ in range(rng.choice([0, 3, 159, 160, 161, 1000]))))
    for k in range(0, 160, 9):
        bad.append(good[-1][:k])
    for _ in range(100):
        b = bytearray(good[-1])
        b[rng.randrange(160)] ^= 1 << rng.randrange(8)
        bad.append(bytes(b))
    body = good[-1][:4] + b'\x09' + good[-1][5:-4]
    bad.append(body + struct.pack('<I', zlib.crc32(body)))
    nan = good[-1][:20] + struct.pack('<d', float('nan')) + good[-1][28:-4]
    bad.append(nan + struct.pack('<I', zlib.crc32(nan)))
    bad += good                                            # replays
    bad.append(tp.pack_state(2, 0.0, sent2))               # reordered (older sequence)
    return bad


class TestFuzz(unittest.TestCase):
    def check_rejections(self, v, bad, foreign):
        """/diagnostics values v after the `bad` datagrams and `foreign` valid foreign ones."""
        self.assertEqual(v['packets received'], 5)
        self.assertEqual(v['rejected datagrams'], len(bad) + foreign)
        reasons = [k for k in v if k.startswith('rejected ') and k not in ('rejected datagrams',
                                                                           'rejected wrench_cmd')]
        self.assertEqual(len(reasons), 10, reasons)
        self.assertEqual(sum(v[k] for k in reasons), len(bad) + foreign)
        self.assertEqual(v['rejected foreign_source'], foreign)
        self.assertEqual(v['rejected size'], sum(len(d) != 160 for d in bad))
        self.assertGreaterEqual(v['rejected crc'], 50)           # most single bit flips
        self.assertGreaterEqual(v['rejected version'], 1)
        self.assertGreaterEqual(v['rejected non_finite'], 1)
        # 5 replays + the reordered packet: the last accepted one replayed is a duplicate, or out of
        # order if the replays came more than resync_after after it
        self.assertEqual(v['rejected duplicate'] + v['rejected out_of_order'], 6)
        self.assertGreaterEqual(v['rejected out_of_order'], 5)
        self.assertEqual(v['rejected wrench_cmd'], 0)

    def test_fuzz(self):
        port, cmd_port = rospy.get_param('~port'), rospy.get_param('~command_port')
        poses = []
        rospy.Subscriber('/touchball/left/pose', PoseStamped, poses.append, queue_size=1000)
        diag = LinkDiagnostics()
        console = FakeConsole(port, cmd_port)
        foreign = FakeConsole(port, cmd_port + 1, source='127.0.0.2')
        time.sleep(1.0)
        good = [console.send(0.001 * k) for k in range(5)]
        time.sleep(0.3)
        self.assertEqual(len(poses), 5)
        n_cmd = len(console.commands)
        self.assertEqual(n_cmd, 5)
        bad = bad_datagrams(good, console.sent[2])
        for data in bad:
            console.send_raw(data)
            time.sleep(0.0005)
        foreign.seq = 1000
        for k in range(20):
            foreign.send(1.0 + 0.001 * k)                      # valid packets, foreign source
        time.sleep(0.5)
        self.assertEqual(len(poses), 5, 'a rejected datagram was published')
        self.assertEqual(len(console.commands), n_cmd, 'a rejected datagram got a command back')
        self.assertEqual(len(foreign.commands), 0)
        _, st, v = diag.fresh()
        self.assertEqual(st.hardware_id, 'console_link')
        self.check_rejections(v, bad, 20)
        # the link still works afterwards
        console.seq = 100
        console.send(2.0)
        time.sleep(0.3)
        self.assertEqual(len(poses), 6)
        # bad force commands (NaN, wrong frame) => zero force, counted; a good one goes through
        wrench = rospy.Publisher('/touchball/left/wrench_cmd', WrenchStamped, queue_size=10)
        time.sleep(1.0)
        rejected_before = diag.fresh()[2]['rejected wrench_cmd']

        def command_after(force, frame):
            # the latch drops commands older than 100 ms: keep publishing while packets flow
            w = WrenchStamped()
            w.header.frame_id = frame
            w.wrench.force.x = force
            n = len(console.commands)
            for _ in range(30):
                w.header.stamp = rospy.Time.now()
                wrench.publish(w)
                time.sleep(0.005)
                console.send(3.0 + 0.001 * console.seq)
                time.sleep(0.005)
            time.sleep(0.2)
            self.assertEqual(len(console.commands), n + 30)
            return tp.unpack_command(console.commands[-1][1]).devices[0]

        good = command_after(1.5, 'touch_left/base')
        self.assertTrue(good.enabled)
        self.assertEqual(good.force, (1.5, 0.0, 0.0))
        for force, frame in ((float('nan'), 'touch_left/base'), (1.5, 'touch_right/base')):
            cmd = command_after(force, frame)
            self.assertFalse(cmd.enabled)
            self.assertEqual(cmd.force, (0.0, 0.0, 0.0))
        self.assertEqual(diag.fresh()[2]['rejected wrench_cmd'], rejected_before + 60)  # 30 NaN + 30 wrong frame
        console.close()
        foreign.close()


if __name__ == '__main__':
    rospy.init_node('touchball_fuzz_test')
    rostest.rosrun('saras_drivers', 'touchball_fuzz', TestFuzz, sys.argv)
