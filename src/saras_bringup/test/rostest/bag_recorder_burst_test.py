#!/usr/bin/env python3
"""rostest: bag_recorder keeps every message of a burst that follows a stall of the recorder.

The failure it guards against: a recorder process that is not scheduled for a while (SIGSTOP here,
CPU starvation on a loaded host) then reads a burst of hundreds of messages from its sockets at
once; a subscription queue shallower than the burst (rosbag record: 100) drops the oldest.
bag_recorder hands each message to its writer in roscpp's network thread and loses nothing; the
reference, rosbag record, loses part of the same burst, which shows that the check detects loss. Also: the bag is closed and renamed on SIGINT, latched topics
are recorded, bad arguments exit 1.
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rosbag
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import String

TOPIC = '/bag_recorder_test/burst'
LATCHED = '/bag_recorder_test/latched'
BURST = 1500          # messages published while the recorder is stopped
STALL = 1.0           # [s]


class BagRecorderBurst(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix='bag_recorder_test_')
        cls.pub = rospy.Publisher(TOPIC, PoseStamped, queue_size=None, tcp_nodelay=True)
        cls.latched = rospy.Publisher(LATCHED, String, queue_size=1, latch=True)
        cls.latched.publish(String(data='set-up'))

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def record_burst(self, name, extra, command=('rosrun', 'saras_bringup', 'bag_recorder')):
        out = os.path.join(self.tmp, name + '.bag')
        # the previous recorder's connection must be gone, or the wait below would see it
        deadline = time.monotonic() + 20.0
        while self.pub.get_num_connections() > 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        self.assertEqual(self.pub.get_num_connections(), 0, 'a previous subscriber is still connected')
        proc = subprocess.Popen(list(command) + ['-O', out, '--tcpnodelay']
                                + extra + [TOPIC, LATCHED, '__name:=rec_' + name])
        try:
            deadline = time.monotonic() + 20.0
            while self.pub.get_num_connections() < 1 and time.monotonic() < deadline:
                time.sleep(0.05)
            self.assertGreater(self.pub.get_num_connections(), 0, 'recorder never subscribed')
            time.sleep(0.5)
            os.kill(proc.pid, signal.SIGSTOP)            # the recorder stalls ...
            msg = PoseStamped()
            t0 = time.monotonic()
            for i in range(BURST):                       # ... while the stream goes on
                msg.header.stamp = rospy.Time.now()
                msg.pose.position.x = float(i)
                self.pub.publish(msg)
            time.sleep(max(0.0, STALL - (time.monotonic() - t0)))
            os.kill(proc.pid, signal.SIGCONT)            # burst: everything the sockets held
            time.sleep(2.0)
            proc.send_signal(signal.SIGINT)
            rc = proc.wait(timeout=30)
        finally:
            if proc.poll() is None:
                os.kill(proc.pid, signal.SIGCONT)
                proc.kill()
        self.assertEqual(rc, 0)
        self.assertTrue(os.path.isfile(out), 'bag not renamed from .active')
        with rosbag.Bag(out) as bag:
            xs = [m.pose.position.x for _, m, _ in bag.read_messages(topics=[TOPIC])]
            latched = [m.data for _, m, _ in bag.read_messages(topics=[LATCHED])]
        return xs, latched

    def test_1_burst_after_a_stall_is_recorded_completely(self):
        xs, latched = self.record_burst('deep', [])
        self.assertEqual(len(xs), BURST)
        self.assertEqual(xs, [float(i) for i in range(BURST)])   # in order, none missing
        self.assertEqual(latched, ['set-up'])

    def test_2_rosbag_record_loses_part_of_the_same_burst(self):
        # the binary itself: `rosbag record` is a Python wrapper that SIGSTOP would not stop
        xs, _ = self.record_burst('reference', [], command=('/usr/lib/rosbag/record',))
        self.assertLess(len(xs), BURST)
        self.assertGreaterEqual(len(xs), 100)

    def test_3_bad_arguments_exit_1(self):
        for args in (['-O', os.path.join(self.tmp, 'x.bag')],                 # no topic
                     ['-O', os.path.join(self.tmp, 'x.bag'), '--queue', '0', TOPIC],
                     ['-O', os.path.join(self.tmp, 'x.bag'), 'relative_topic'],
                     ['-O', '/nonexistent_dir/x.bag', TOPIC]):
            rc = subprocess.call(['rosrun', 'saras_bringup', 'bag_recorder'] + args + ['__name:=rec_bad'],
                                 timeout=30)
            self.assertEqual(rc, 1, args)


if __name__ == '__main__':
    rospy.init_node('bag_recorder_burst_test')
    rostest.rosrun('saras_bringup', 'bag_recorder_burst', BagRecorderBurst, sys.argv)
