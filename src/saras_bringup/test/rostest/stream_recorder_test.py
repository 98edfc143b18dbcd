#!/usr/bin/env python3
"""stream_recorder.test: what the StreamRecorder nodelet writes, and when it refuses to load.

Messages come over TCP here (the test node is another process); in the platform the publishers are
nodelets of the same manager and the same subscriptions receive pointers. Counts are exact: every
message is published after the nodelet's subscription is connected.
"""
import os
import signal
import subprocess
import sys
import time
import unittest
import xmlrpc.client

import rosbag
import rospy
import rosgraph
import rostest
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Float64, String

MANAGER = '/rec_manager'


def wait_connected(pub, timeout=20.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end and pub.get_num_connections() == 0:
        time.sleep(0.05)
    return pub.get_num_connections() > 0


class StreamRecorderTest(unittest.TestCase):
    def test_1_records_typed_other_and_late_topics(self):
        out = rospy.get_param('~output')
        if os.path.exists(out):     # a previous run's
            os.remove(out)
        pose = rospy.Publisher('/a_pose', PoseStamped, queue_size=1000)
        text = rospy.Publisher('/a_text', String, queue_size=100)
        self.assertTrue(wait_connected(pose), 'the nodelet did not subscribe /a_pose')
        self.assertTrue(wait_connected(text), 'the nodelet did not subscribe /a_text (type not in its table)')
        energy = rospy.Publisher('/late_energy', Float64, queue_size=100)   # advertised after the start
        self.assertTrue(wait_connected(energy), 'the nodelet did not subscribe the late topic')
        for i in range(300):
            m = PoseStamped()
            m.header.stamp = rospy.Time.now()
            m.header.frame_id = 'world'
            m.pose.position.x = 0.001 * i
            pose.publish(m)
            if i % 10 == 0:
                text.publish(String('t%d' % i))
                energy.publish(Float64(float(i)))
            time.sleep(0.002)
        time.sleep(1.0)
        self.assertTrue(os.path.exists(out + '.active'))
        # SIGINT to the loader (as roslaunch stops it): it unloads the nodelet, which closes the bag
        uri = rosgraph.Master('/stream_recorder_test').lookupNode('/part_recorder')
        os.kill(xmlrpc.client.ServerProxy(uri).getPid('/x')[2], signal.SIGINT)
        end = time.monotonic() + 20.0
        while time.monotonic() < end and os.path.exists(out + '.active'):
            time.sleep(0.1)
        self.assertFalse(os.path.exists(out + '.active'), 'the bag was not closed at unload')
        self.assertTrue(os.path.exists(out), 'the bag was not renamed at unload')
        with rosbag.Bag(out) as bag:
            info = bag.get_type_and_topic_info().topics
            self.assertEqual(info['/a_pose'].msg_type, 'geometry_msgs/PoseStamped')
            self.assertEqual(info['/a_pose'].message_count, 300)
            self.assertEqual(info['/a_text'].message_count, 30)
            self.assertEqual(info['/late_energy'].message_count, 30)
            xs = [m.pose.position.x for _, m, _ in bag.read_messages(topics=['/a_pose'])]
            self.assertEqual(xs, [0.001 * i for i in range(300)])
            texts = [m.data for _, m, _ in bag.read_messages(topics=['/a_text'])]
            self.assertEqual(texts, ['t%d' % i for i in range(0, 300, 10)])
        os.remove(out)

    def test_2_bad_parameters_refuse_the_nodelet(self):
        for i, args in enumerate((['_output:=/tmp/x_bad.bag', '_topics:=relative/topic'],
                                  ['_topics:=/a'],
                                  ['_output:=/nonexistent_dir/x.bag', '_topics:=/a'])):
            p = subprocess.run(['rosrun', 'nodelet', 'nodelet', 'load', 'saras_bringup/StreamRecorder', MANAGER,
                                '__name:=bad_recorder_%d' % i] + args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               timeout=60)
            self.assertNotEqual(p.returncode, 0, ' '.join(args))

if __name__ == '__main__':
    rospy.init_node('stream_recorder_test')
    rostest.rosrun('saras_bringup', 'stream_recorder', StreamRecorderTest, sys.argv)
