#!/usr/bin/env python3
"""rostest: dvrk_sim ~publish_link_tf equals robot_state_publisher (the reference, on /tf_ref and
/tf_static_ref) for every joint transform of PSM1, PSM2 and ECM at the same stamp, at the
simulator's ~link_tf_rate (50 Hz, robot_state_publisher's default publish_frequency; the
reference publishes every joint-state sample), with the fixed joints (tool tips, endoscope optical frames) on /tf_static."""
import sys
import unittest

import numpy as np
import rospy
import rostest
from tf2_msgs.msg import TFMessage

RATE = 50.0      # [Hz] dvrk_sim ~link_tf_rate (config/dvrk_sim.yaml; joint states at 100 Hz)
WINDOW = 4.0     # [s]
TOL = 1e-9       # [m] / quaternion component


def vec(t):
    tr, r = t.transform.translation, t.transform.rotation
    return np.array([tr.x, tr.y, tr.z]), np.array([r.x, r.y, r.z, r.w])


class LinkTfTest(unittest.TestCase):
    def test_equals_robot_state_publisher(self):
        ours, ref, static, static_ref = {}, {}, {}, {}

        def store(d):
            def cb(msg):
                for t in msg.transforms:
                    d[(t.header.frame_id, t.child_frame_id, t.header.stamp.to_nsec())] = vec(t)
            return cb

        def store_static(d):
            def cb(msg):
                for t in msg.transforms:
                    d[(t.header.frame_id, t.child_frame_id)] = vec(t)
            return cb
        subs = [rospy.Subscriber('/tf', TFMessage, store(ours), queue_size=1000, tcp_nodelay=True),
                rospy.Subscriber('/tf_ref', TFMessage, store(ref), queue_size=1000, tcp_nodelay=True),
                rospy.Subscriber('/tf_static', TFMessage, store_static(static), queue_size=10),
                rospy.Subscriber('/tf_static_ref', TFMessage, store_static(static_ref), queue_size=10)]
        rospy.sleep(1.0)
        n0 = len(ours)
        t0 = rospy.get_time()
        rospy.sleep(WINDOW)
        n1, t1 = len(ours), rospy.get_time()
        # stop the callbacks, then work on copies (dict() copies under the GIL)
        for s in subs:
            s.unregister()
        rospy.sleep(0.2)
        ours, ref, static, static_ref = dict(ours), dict(ref), dict(static), dict(static_ref)
        common = set(ours) & set(ref)
        self.assertGreater(len(common), 50, 'no common (frame, stamp) samples with robot_state_publisher')
        worst = 0.0
        for k in common:
            (p, q), (pr, qr) = ours[k], ref[k]
            worst = max(worst, np.abs(p - pr).max(), min(np.abs(q - qr).max(), np.abs(q + qr).max()))
        self.assertLess(worst, TOL, 'largest difference %.3g' % worst)
        # every arm's moving joints are broadcast, at the link TF rate
        children = {k[1] for k in ours}
        for arm in ('PSM1', 'PSM2', 'ECM'):
            self.assertTrue(any(c.startswith(arm + '/') for c in children), arm)
        per_frame = {}
        for k in ours:
            per_frame.setdefault(k[1], set()).add(k[2])
        psm1 = max((len(v) for c, v in per_frame.items() if c.startswith('PSM1/')), default=0)
        self.assertGreater(psm1, 0.7 * RATE * (WINDOW + 1.0), 'PSM1 joint TF samples: %d' % psm1)
        self.assertLess(psm1, 1.2 * RATE * (WINDOW + 1.5), 'PSM1 joint TF samples: %d (rate limit)' % psm1)
        self.assertGreater(n1 - n0, 0.7 * RATE * (t1 - t0), 'TF samples in the window: %d' % (n1 - n0))
        # fixed joints: latched, identical to robot_state_publisher's
        self.assertIn('endoscope/left_optical_frame', {k[1] for k in static})
        self.assertIn('endoscope/right_optical_frame', {k[1] for k in static})
        self.assertTrue(static_ref, 'reference published no static transforms')
        for k, (pr, qr) in static_ref.items():
            self.assertIn(k, static)
            p, q = static[k]
            self.assertLess(np.abs(p - pr).max(), TOL, k)
            self.assertLess(min(np.abs(q - qr).max(), np.abs(q + qr).max()), TOL, k)


if __name__ == '__main__':
    rospy.init_node('dvrk_link_tf_check')
    rostest.rosrun('saras_simulation', 'dvrk_link_tf_check', LinkTfTest, sys.argv)
