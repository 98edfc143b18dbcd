#!/usr/bin/env python3
"""rostest: bag_recorder faults. A disk that runs full (a real 8 MB tmpfs when run as root, and the
--min-free threshold on any disk) stops the writing with an error naming the filesystem, leaves an
indexed, readable bag up to the fault and counts the messages lost after it; SIGTERM leaves an
indexed bag; --split-size writes a sequence of indexed bags.
"""
import glob
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
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from std_msgs.msg import String

TOPIC = '/bag_recorder_faults_test/data'
PAYLOAD = 'x' * 50000      # 50 kB messages: a small disk fills in seconds


class BagRecorderFaults(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix='bag_recorder_faults_')
        cls.pub = rospy.Publisher(TOPIC, String, queue_size=100)
        cls.status = []
        rospy.Subscriber('/diagnostics', DiagnosticArray, lambda m: cls.status.extend(m.status))

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def start(self, out, extra, name):
        deadline = time.monotonic() + 20.0
        while self.pub.get_num_connections() > 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        proc = subprocess.Popen(['rosrun', 'saras_bringup', 'bag_recorder', '-O', out] + extra +
                                [TOPIC, '__name:=' + name], stdout=subprocess.PIPE, universal_newlines=True)
        deadline = time.monotonic() + 20.0
        while self.pub.get_num_connections() < 1 and time.monotonic() < deadline:
            time.sleep(0.05)
        self.assertGreater(self.pub.get_num_connections(), 0, 'recorder never subscribed')
        return proc

    def publish(self, n, rate=200.0):
        for i in range(n):
            self.pub.publish(String(data='%06d' % i + PAYLOAD))
            time.sleep(1.0 / rate)

    def stop(self, proc, sig=signal.SIGINT):
        proc.send_signal(sig)
        out, _ = proc.communicate(timeout=60)
        return proc.returncode, out

    def check_readable(self, path):
        self.assertTrue(os.path.isfile(path), 'no closed bag %s (left: %s)' % (path, os.listdir(os.path.dirname(path))))
        with rosbag.Bag(path) as bag:               # opening reads the index: fails on an unindexed bag
            return [int(m.data[:6]) for _, m, _ in bag.read_messages(topics=[TOPIC])]

    def fault_status(self, name):
        return [s for s in self.status if s.name.startswith(name) and s.level == DiagnosticStatus.ERROR
                and 'disk fault on' in s.message]

    def test_1_min_free_threshold_stops_closes_and_reports(self):
        out = os.path.join(self.tmp, 'threshold.bag')
        # every real disk has less than 1 TB free: the threshold fires at the first message
        proc = self.start(out, ['--min-free', '1048576'], 'rec_threshold')
        self.publish(50)
        time.sleep(1.5)
        rc, text = self.stop(proc)
        self.assertEqual(rc, 1, 'a recording cut by a disk fault must not exit 0')
        self.assertEqual(self.check_readable(out), [])
        self.assertIn('lost after a disk fault', text)
        self.assertRegex(text, r'lost after the disk fault: %s [1-9]' % TOPIC)
        st = self.fault_status('rec_threshold')
        self.assertTrue(st, 'no ERROR on /diagnostics')
        self.assertIn('--min-free', st[-1].message)
        self.assertRegex(st[-1].message, r'disk fault on /\S* \(\S+\)')  # mount point (device)

    def test_2_sigterm_leaves_an_indexed_bag(self):
        out = os.path.join(self.tmp, 'term.bag')
        proc = self.start(out, [], 'rec_term')
        self.publish(40)
        time.sleep(1.0)
        rc, _ = self.stop(proc, signal.SIGTERM)
        self.assertEqual(rc, 0)
        self.assertEqual(self.check_readable(out), list(range(40)))
        self.assertFalse(os.path.exists(out + '.active'))

    def test_3_split_by_size(self):
        out = os.path.join(self.tmp, 'split.bag')
        proc = self.start(out, ['--split-size', '1', '--chunksize', '256'], 'rec_split')
        self.publish(100)          # 5 MB
        time.sleep(1.0)
        rc, _ = self.stop(proc)
        self.assertEqual(rc, 0)
        parts = sorted(glob.glob(os.path.join(self.tmp, 'split_*.bag')), key=lambda p: int(p[:-4].split('_')[-1]))
        self.assertGreaterEqual(len(parts), 3, parts)
        got = []
        for p in parts:
            got += self.check_readable(p)
        self.assertEqual(got, list(range(100)))

    @unittest.skipUnless(os.geteuid() == 0, 'mounting a tmpfs needs root')
    def test_4_real_full_disk(self):
        mnt = os.path.join(self.tmp, 'tiny')
        os.mkdir(mnt)
        subprocess.check_call(['mount', '-t', 'tmpfs', '-o', 'size=8m', 'tmpfs', mnt])
        try:
            out = os.path.join(mnt, 'full.bag')
            proc = self.start(out, ['--min-free', '1', '--chunksize', '256'], 'rec_full')
            self.publish(300)       # 15 MB into 8 MB
            time.sleep(1.5)
            rc, text = self.stop(proc)
            self.assertEqual(rc, 1)
            self.assertIn('disk fault on %s (tmpfs)' % mnt, text)
            got = self.check_readable(out)
            self.assertGreater(len(got), 50)            # kept up to the fault ...
            self.assertEqual(got, list(range(len(got))))  # ... in order, nothing missing before it
            self.assertRegex(text, r'lost after the disk fault: %s [1-9]' % TOPIC)
        finally:
            subprocess.call(['umount', '-l', mnt])


if __name__ == '__main__':
    rospy.init_node('bag_recorder_faults_test')
    rostest.rosrun('saras_bringup', 'bag_recorder_faults', BagRecorderFaults, sys.argv)
