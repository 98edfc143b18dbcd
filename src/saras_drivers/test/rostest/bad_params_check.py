#!/usr/bin/env python3
"""rostest: microphone rejects bad parameters at start-up with exit status 2 and a message naming
the parameter."""
import subprocess
import sys
import unittest

import rospy
import rostest

CASES = [
    ('microphone', ['_chunk_ms:=0.01'], '~chunk_ms'),
    ('microphone', ['_sample_rate:=100'], '~sample_rate'),
]


class BadParamsTest(unittest.TestCase):
    def test_bad_parameters_are_fatal_and_named(self):
        for i, (node, args, needle) in enumerate(CASES):
            p = subprocess.run(['rosrun', 'saras_drivers', node, '__name:=bad_%d' % i] + args,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
            out = p.stdout.decode('utf-8', 'replace')
            self.assertEqual(p.returncode, 2, '%s %s: exit %d\n%s' % (node, args, p.returncode, out))
            self.assertIn(needle, out, '%s %s: message does not name %s:\n%s' % (node, args, needle, out))


if __name__ == '__main__':
    rospy.init_node('bad_params_check')
    rostest.rosrun('saras_drivers', 'bad_params', BadParamsTest, sys.argv)
