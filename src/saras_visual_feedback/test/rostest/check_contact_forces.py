#!/usr/bin/env python3
"""rostest checker of contact_forces (see ../contact_forces.test): one node per side.

Publishes contacts on /mesa_left/contact only and checks both sides' contact_force: the value
depth*K_skin*direction/|direction| at 60 Hz, zero for the side without contact, zero once the
contact is stale, and NaN / zero-length / negative-depth contacts rejected (no NaN force, the node
keeps publishing, /diagnostics counts them).
"""
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist, Vector3
from saras_msgs.msg import Contact
from diagnostics import DiagnosticStatus, DiagnosticsRecorder

K_SKIN = 500.0  # config/contact_forces.yaml


class Recorder:
    def __init__(self, topic):
        self.lock = threading.Lock()
        self.msgs = []
        rospy.Subscriber(topic, Twist, self.cb, queue_size=200)

    def cb(self, msg):
        with self.lock:
            self.msgs.append((time.time(), msg))

    def since(self, t):
        with self.lock:
            return [m for (s, m) in self.msgs if s >= t]


def contact(depth, x, y, z):
    return Contact(depth=depth, direction=Vector3(x, y, z))


class TestContactForces(unittest.TestCase):
    def test_contact_forces(self):
        pub = rospy.Publisher('/mesa_left/contact', Contact, queue_size=10)
        diagnostics = DiagnosticsRecorder('mesa_left/contact_forces')
        left = Recorder('/mesa_left/contact_force')
        right = Recorder('/mesa_right/contact_force')
        end = time.time() + 20.0
        while time.time() < end and (pub.get_num_connections() == 0 or not left.since(0) or not right.since(0)):
            time.sleep(0.05)
        self.assertGreater(pub.get_num_connections(), 0, 'contact_forces not subscribed')

        def stream(msg, seconds, rate=30.0):
            t_end = time.time() + seconds
            while time.time() < t_end:
                pub.publish(msg)
                time.sleep(1.0 / rate)

        # 1 cm along (0, 3, 4): 5 N -> (0, 3, 4) N.
        stream(contact(0.01, 0.0, 3.0, 4.0), 1.0)
        t0 = time.time()
        stream(contact(0.01, 0.0, 3.0, 4.0), 3.0)
        got = left.since(t0)
        rate = len(got) / (time.time() - t0)
        self.assertGreater(rate, 54.0)
        self.assertLess(rate, 66.0)
        for m in got:
            self.assertAlmostEqual(m.linear.x, 0.0, places=9)
            self.assertAlmostEqual(m.linear.y, 3.0, places=9)
            self.assertAlmostEqual(m.linear.z, 4.0, places=9)
            self.assertEqual((m.angular.x, m.angular.y, m.angular.z), (0.0, 0.0, 0.0))
        r = right.since(t0)
        self.assertGreater(len(r), 150)
        self.assertTrue(all(m.linear.x == m.linear.y == m.linear.z == 0.0 for m in r), 'no contact must give 0 N')

        # Bad input only: rejected; the last valid force holds until stale, then zero, never NaN.
        t1 = time.time()
        for _ in range(20):
            for bad in (contact(0.01, 0.0, 0.0, 0.0), contact(float('nan'), 0.0, 0.0, 1.0),
                        contact(0.01, float('inf'), 0.0, 1.0), contact(-0.01, 0.0, 0.0, 1.0)):
                pub.publish(bad)
            time.sleep(0.05)
        got = left.since(t1)
        self.assertGreater(len(got), 50, 'contact_forces stopped publishing under bad input')
        for m in got:
            self.assertTrue(all(math.isfinite(v) for v in (m.linear.x, m.linear.y, m.linear.z)))
        late = left.since(t1 + 0.2 + 0.1)  # stale_timeout 0.2 s + margin
        self.assertTrue(late and all(m.linear.x == m.linear.y == m.linear.z == 0.0 for m in late), 'stale force not zero')
        self.assertTrue(diagnostics.statuses, 'no mesa_left/contact_forces status on /diagnostics')

        def rejected():
            return int(DiagnosticsRecorder.values(diagnostics.statuses[-1])['rejected contacts'])
        end = time.time() + 3.0  # published every diagnostic_period (1 s)
        while time.time() < end and (rejected() < 80 or diagnostics.statuses[-1].level != DiagnosticStatus.STALE):
            time.sleep(0.1)
        self.assertEqual(rejected(), 80)
        self.assertEqual(diagnostics.statuses[-1].level, DiagnosticStatus.STALE)

        # Valid contact again: force again (no latching of the bad state), then stop: zero.
        stream(contact(0.004, -2.0, 0.0, 0.0), 0.5)
        m = left.since(time.time() - 0.1)[-1]
        self.assertAlmostEqual(m.linear.x, -0.004 * K_SKIN, places=9)
        t2 = time.time()
        time.sleep(0.6)
        self.assertTrue(all(m.linear.x == 0.0 for m in left.since(t2 + 0.3)))


if __name__ == '__main__':
    rospy.init_node('check_contact_forces')
    rostest.rosrun('saras_visual_feedback', 'check_contact_forces', TestContactForces, sys.argv)
