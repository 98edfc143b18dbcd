#!/usr/bin/env python3
"""rostest checker: /visual_feedback/{left,right}/image/compressed carries each augmented frame
exactly once, from the encoder /diagnostics names (image_transport's plugin or the nodelet)."""
import collections
import subprocess
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import CompressedImage

FRAMES = 40  # per eye, ~1.3 s at 30 Hz


def plugin_installed():
    return subprocess.call(['rospack', 'find', 'compressed_image_transport'], stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL) == 0


class CheckCompressed(unittest.TestCase):
    def test_one_stream_per_eye(self):
        counts = {eye: collections.Counter() for eye in ('left', 'right')}
        sources = []

        def diagnostics(msg):
            for s in msg.status:
                if s.name.startswith('visual_feedback') and s.hardware_id == 'visual_feedback':
                    sources.extend(v.value for v in s.values if v.key == 'compressed stream')

        rospy.Subscriber('/diagnostics', DiagnosticArray, diagnostics, queue_size=50)
        for eye in counts:
            rospy.Subscriber('/visual_feedback/%s/image/compressed' % eye, CompressedImage,
                             lambda m, c=counts[eye]: c.update([m.header.stamp.to_nsec()]), queue_size=100)
        deadline = rospy.Time.now() + rospy.Duration(40.0)
        while not rospy.is_shutdown() and rospy.Time.now() < deadline:
            if min(len(c) for c in counts.values()) >= FRAMES and sources:
                break
            rospy.sleep(0.1)
        rospy.sleep(0.5)  # a duplicate of the last frames would arrive right after them
        for eye, c in counts.items():
            self.assertGreaterEqual(len(c), FRAMES, '%s: %d frames on /compressed' % (eye, len(c)))
            twice = [stamp for stamp, n in c.items() if n != 1]
            self.assertEqual(twice, [], '%s: %d of %d frames not exactly once on /compressed'
                             % (eye, len(twice), len(c)))
        self.assertTrue(sources, 'no "compressed stream" on /diagnostics')
        plugin = rospy.get_param('~plugin', True) and plugin_installed()
        self.assertEqual(sources[-1], 'image_transport' if plugin else 'visual_feedback')


if __name__ == '__main__':
    rospy.init_node('check_compressed')
    rostest.rosrun('saras_visual_feedback', 'check_compressed', CheckCompressed)
