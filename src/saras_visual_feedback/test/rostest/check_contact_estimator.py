#!/usr/bin/env python3
"""rostest: ContactEstimator on untextured images is unknown, never a confident zero (see
contact_estimator.test)."""
import math
import sys
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from saras_msgs.msg import Contact
from std_msgs.msg import Float64MultiArray

SCENE_REASONS = {3, 4, 5, 6}  # ContactUnknown: out of view, occluded, no texture, no surface
NO_POSE = 2                   # ContactUnknown::kNoPose: the pose at the image stamp is missing (a busy host)


class TestContactEstimator(unittest.TestCase):
    def test_untextured_scene_is_unknown(self):
        estimates, contacts, status = [], [], []
        rospy.Subscriber('/mesa_left/contact_estimate', Float64MultiArray, estimates.append)
        rospy.Subscriber('/mesa_left/contact', Contact, contacts.append)
        rospy.Subscriber('/diagnostics', DiagnosticArray,
                         lambda m: status.extend(s for s in m.status if 'contact_estimator' in s.name))
        deadline = time.time() + 30.0
        while time.time() < deadline and len(estimates) < 10:
            time.sleep(0.1)
        self.assertGreaterEqual(len(estimates), 10, 'no contact estimates (stereo pairs not processed?)')
        del estimates[:]
        start = time.time()
        time.sleep(3.0)
        rate = len(estimates) / (time.time() - start)
        self.assertGreater(rate, 10.0, 'estimates at %.1f Hz for 30 Hz stereo pairs' % rate)
        stamps = [e.data[0] for e in estimates]
        self.assertEqual(len(stamps), len(set(stamps)), 'one estimate per stereo pair')
        for e in estimates:
            self.assertEqual(len(e.data), 19)
            self.assertTrue(all(math.isnan(v) for v in e.data[9:15]), 'unknown: no surface point or normal')
            self.assertEqual(e.data[1], 0.0, 'state must be unknown on untextured images: %s' % list(e.data))
            self.assertEqual(e.data[4], 0.0, 'unknown estimates have confidence 0')
            self.assertIn(int(e.data[8]), SCENE_REASONS | {NO_POSE})
        # the untextured scene itself is judged (not only missing poses)
        self.assertTrue(any(int(e.data[8]) in SCENE_REASONS for e in estimates),
                        'no estimate judged the scene: %s' % sorted({int(e.data[8]) for e in estimates}))
        self.assertEqual(contacts, [], 'an unknown contact must not be published as a Contact (depth 0)')
        self.assertTrue(status, 'no /diagnostics status of the contact estimator')
        self.assertEqual(status[-1].hardware_id, 'visual_feedback')
        self.assertEqual(status[-1].level, DiagnosticStatus.WARN, status[-1].message)


if __name__ == '__main__':
    rospy.init_node('check_contact_estimator')
    rostest.rosrun('saras_visual_feedback', 'check_contact_estimator', TestContactEstimator, sys.argv)
