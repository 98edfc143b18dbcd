#!/usr/bin/env python3
"""rostest: attacks on the console link. Forged (right CRC, v1), replayed, reordered, bit-flipped,
truncated, oversized, other-key, old-session and foreign datagrams never reach a topic, never get
a command packet back, and every one is counted on /diagnostics under its reason; bad force
commands are counted there too; under a flood of such datagrams the legitimate console keeps
control at its rate."""
import random
import struct
import sys
import threading
import time
import unittest
import zlib

import rospy
import rostest
from geometry_msgs.msg import PoseStamped, WrenchStamped

from saras_drivers import touchball_protocol as tp
from touchball_fake_console import FakeConsole, LinkDiagnostics, device

OTHER_KEY = tp.Mac(bytes(range(32)))          # a valid MAC under another key


def v1_packet(seq, t, devices):
    """The old, unauthenticated protocol version 1 state packet (160 bytes, CRC-32): a forgery
    anybody can compute."""
    (lp, lq, lc, _, _), (rp, rq, rc, _, _) = devices
    body = struct.pack('<4sBBHId3d4ddI3d4ddI', b'TBAL', 1, 1, 0, seq, t, *lp, *lq, lc, 0, *rp, *rq, rc, 0)
    return body + struct.pack('<I', zlib.crc32(body))


def bad_datagrams(console, good, sent2):
    """Random, truncated, oversized, bit-flipped, v1 (right CRC), other-key, old-session, NaN,
    replayed and reordered datagrams, built from the accepted packets `good` (sequence 0-4)."""
    rng = random.Random(7)
    mac, session = console.mac, console.session_nonce
    bad = []
    for _ in range(300):
        bad.append(bytes(rng.getrandbits(8) for _ in range(rng.choice([0, 3, 44, 179, 180, 181, 1000]))))
    for k in range(0, 180, 9):
        bad.append(good[-1][:k])                                   # truncated
    bad.append(good[-1] + b'\0')                                   # oversized
    bad.append(good[-1] * 8)
    for _ in range(100):
        b = bytearray(good[-1])
        b[rng.randrange(180)] ^= 1 << rng.randrange(8)              # bit flips
        bad.append(bytes(b))
    bad += [v1_packet(100 + k, console.epoch + 1.0, sent2) for k in range(10)]       # forged, right CRC
    bad += [tp.pack_state(OTHER_KEY, session, 200 + k, console.epoch + 1.0, sent2) for k in range(10)]
    bad += [tp.pack_state(mac, session ^ 1, 300 + k, console.epoch + 1.0, sent2) for k in range(10)]  # other session
    nan = list(sent2)
    nan[0] = tp.DeviceState((float('nan'), 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), 0.0, False, False)
    bad.append(tp.pack_state(mac, session, 400, console.epoch + 1.0, nan))
    bad.append(tp.pack_hello(mac, 12345, 0, console.epoch))        # a hello while the session streams
    bad += good                                                    # replays
    bad.append(tp.pack_state(mac, session, 2, console.epoch, sent2))   # reordered (older sequence)
    return bad


class TestFuzz(unittest.TestCase):
    def check_rejections(self, after, before, bad, foreign):
        """/diagnostics values after the `bad` datagrams and `foreign` valid foreign ones (counters
        relative to `before`)."""
        v = dict((k, x - before.get(k, 0)) for k, x in after.items() if isinstance(x, int))
        self.assertEqual(v['packets received'], 5)
        self.assertEqual(v['rejected datagrams'], len(bad) + foreign)
        reasons = [k for k in v if k.startswith('rejected ') and k not in ('rejected datagrams',
                                                                           'rejected wrench_cmd')]
        self.assertEqual(len(reasons), len(tp.REJECT_REASONS), reasons)
        self.assertEqual(sum(v[k] for k in reasons), len(bad) + foreign)
        self.assertEqual(v['rejected foreign_source'], foreign)
        self.assertGreaterEqual(v['rejected size'], 20 + 2)         # truncated, oversized
        self.assertGreaterEqual(v['rejected mac'], 80 + 10)       # bit flips (most), other key
        self.assertGreaterEqual(v['rejected version'], 10)        # v1 with the right CRC
        self.assertEqual(v['rejected session'], 10 + 1)           # other session, hello while streaming
        self.assertEqual(v['rejected non_finite'], 1)
        self.assertEqual(v['rejected duplicate'] + v['rejected out_of_order'], 6)   # 5 replays + reordered
        self.assertEqual(v['rejected wrench_cmd'], 0)

    def test_fuzz(self):
        port, cmd_port = rospy.get_param('~port'), rospy.get_param('~command_port')
        poses = []
        rospy.Subscriber('/touchball/left/pose', PoseStamped, poses.append, queue_size=1000)
        diag = LinkDiagnostics()
        console = FakeConsole(port, cmd_port)
        foreign = FakeConsole(port, cmd_port + 1, source='127.0.0.2')
        time.sleep(1.5)                                       # a previous session expires (resync_after)
        before = diag.fresh()[2]
        self.assertTrue(console.connect(), 'no session (handshake)')
        foreign.session.session = console.session_nonce       # even a stolen session: foreign source
        good = [console.send(0.001 * k) for k in range(5)]
        time.sleep(0.3)
        self.assertEqual(len(poses), 5)
        n_cmd = len(console.commands)
        self.assertEqual(n_cmd, 5)
        bad = bad_datagrams(console, good, console.sent[2])
        for data in bad:
            console.send_raw(data)
            time.sleep(0.0005)
        foreign.seq = 1000
        for k in range(20):
            foreign.send(1.0 + 0.001 * k)                      # valid packets, foreign source
        time.sleep(0.5)
        self.assertEqual(len(poses), 5, 'a rejected datagram was published')
        self.assertEqual(len(console.commands), n_cmd, 'a rejected datagram got a command back')
        self.assertEqual(len(foreign.received), 0)
        _, st, v = diag.fresh()
        self.assertEqual(st.hardware_id, 'console_link')
        self.check_rejections(v, before, bad, 20)
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
            return tp.unpack_command(console.commands[-1][1], console.mac).devices[0]

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

    def test_flood_keeps_the_operator_in_control(self):
        """10 000 forged datagrams/s while the console streams at 250 Hz: every console packet is
        accepted and published, none of the flood is."""
        port, cmd_port = rospy.get_param('~port'), rospy.get_param('~command_port')
        poses = []
        rospy.Subscriber('/touchball/left/pose', PoseStamped, poses.append, queue_size=10000)
        diag = LinkDiagnostics()
        console = FakeConsole(port, cmd_port)          # the receiver answers on its command_port
        time.sleep(1.5)                                       # the previous session expires (resync_after)
        self.assertTrue(console.connect(), 'no session (handshake)')
        before = diag.fresh()[2]
        forged = [tp.pack_state(OTHER_KEY, console.session_nonce, k, console.epoch, (device(0.0), device(0.0)))
                  for k in range(50)]
        stop = threading.Event()
        flooded = [0]

        def flood():
            period, t0 = 1e-4, time.monotonic()
            while not stop.is_set():
                for d in forged:
                    console.send_raw(d)
                    flooded[0] += 1
                lag = t0 + flooded[0] * period - time.monotonic()
                if lag > 0:
                    time.sleep(lag)
        attacker = threading.Thread(target=flood, daemon=True)
        attacker.start()
        seq0 = console.seq
        console.stream(250.0, 3.0, t0=10.0)
        stop.set()
        attacker.join(2.0)
        sent = console.seq - seq0
        time.sleep(0.5)
        after = diag.fresh()[2]
        rospy.loginfo('flood: %d forged datagrams in 3 s; console sent %d, accepted %d, published %d',
                      flooded[0], sent, after['packets received'] - before['packets received'], len(poses))
        self.assertGreater(flooded[0], 5000)
        self.assertGreaterEqual(after['packets received'] - before['packets received'], int(0.95 * sent))
        self.assertGreaterEqual(len(poses), int(0.95 * sent))
        self.assertLessEqual(len(poses), sent)
        self.assertGreaterEqual(after['rejected mac'] - before['rejected mac'], int(0.5 * flooded[0]))
        console.close()


if __name__ == '__main__':
    rospy.init_node('touchball_fuzz_test')
    rostest.rosrun('saras_drivers', 'touchball_fuzz', TestFuzz, sys.argv)
