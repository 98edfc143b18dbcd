#!/usr/bin/env python3
"""rostest: the receiver nodelet loaded into /teleop/teleop_manager publishes under the contract's
names (/touchball/<side>/..., /tf, /touchball/status), streams the packets of a fake console
(250 Hz, from this test node) and is OK on touchball/status and on /diagnostics (under the
nodelet's name, hardware_id console_link)."""
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from saras_msgs.msg import ComponentStatus, HapticDeviceState
from tf2_msgs.msg import TFMessage

from touchball_fake_console import FakeConsole, LinkDiagnostics

RATE = 250.0  # [Hz] console stream


class TestNodelet(unittest.TestCase):
    def test_names_and_stream(self):
        states, poses, tfs, status = [], [], [], []
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, states.append, queue_size=1000)
        rospy.Subscriber('/touchball/right/pose', PoseStamped, poses.append, queue_size=1000)
        rospy.Subscriber('/tf', TFMessage, tfs.append, queue_size=1000)
        rospy.Subscriber('/touchball/status', ComponentStatus, status.append, queue_size=100)
        diag = LinkDiagnostics()
        console = FakeConsole(rospy.get_param('~port'), rospy.get_param('~command_port'))
        stop = threading.Event()

        def stream():
            k = 0
            while not stop.wait(1.0 / RATE):
                console.send(k / RATE)
                k += 1
        streamer = threading.Thread(target=stream, daemon=True)
        streamer.start()

        def finish():
            stop.set()
            streamer.join(1.0)
            console.close()
        self.addCleanup(finish)
        end = time.monotonic() + 40.0
        while time.monotonic() < end and (len(states) < 100 or not status or status[-1].level != 0):
            time.sleep(0.1)
        self.assertGreaterEqual(len(states), 100)
        self.assertGreater(len(poses), 0)
        self.assertEqual(status[-1].level, ComponentStatus.OK, status[-1].message)
        st = [m for m in states if not m.stale][-1]
        self.assertEqual(st.header.frame_id, 'touch_left/base')
        self.assertEqual(st.device, 'left')
        self.assertEqual(poses[-1].header.frame_id, 'touch_right/base')
        children = set(t.child_frame_id for m in tfs for t in m.transforms)
        self.assertIn('touch_left/stylus', children)
        topics = [t for t, _ in rospy.get_published_topics()]
        self.assertFalse([t for t in topics if t.startswith('/teleop/touchball')],
                         'receiver topics moved into the manager namespace: %s' % topics)
        self.assertIn('/touch_left/joint_states', topics)
        ok = diag.wait_for(lambda st, v: st.level == st.OK and v.get('packets received', 0) > 100, timeout=20.0,
                           after=0.0)
        self.assertIsNotNone(ok, 'no OK /diagnostics report of %s' % diag.name)
        self.assertEqual(ok[1].hardware_id, 'console_link')
        self.assertEqual(ok[1].message, 'streaming')


if __name__ == '__main__':
    rospy.init_node('touchball_nodelet_test')
    rostest.rosrun('saras_drivers', 'touchball_nodelet', TestNodelet, sys.argv)
