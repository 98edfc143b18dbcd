#!/usr/bin/env python3
"""rostest: dvrk_sim, contact_sim and microphone_sim reject bad parameters at start-up
with exit status 2 and a message naming the parameter."""
import subprocess
import sys
import unittest

import rospy
import rostest

CASES = [
    ('dvrk_sim', ['_rate:=-5'], '~rate'),
    ('dvrk_sim', ['_bag:=/nonexistent/x.bag'], '~bag'),
    ('dvrk_sim', ['_publish_link_tf:=true', '_publish_tf:=true'], '~publish_tf and ~publish_link_tf are exclusive'),
    ('dvrk_sim', ['_publish_link_tf:=true', '_robot_description_param:=/nowhere/{arm}/urdf'],
     '/nowhere/PSM1/urdf'),
    ('dvrk_sim', ['_publish_link_tf:=2'], 'parameter ~publish_link_tf = 2 is invalid: must be true or false'),
    ('dvrk_sim', ['_max_catch_up:=0'],
     'parameter ~max_catch_up = 0 [samples] is invalid: must be integer in [1, 1000]'),
    ('dvrk_sim', ['_crtk_ns:=PSM'], '~crtk_ns'),
    ('dvrk_sim', ['_robot_description_param:=/PSM1/robot_description'], '~robot_description_param'),
    ('dvrk_sim', ['_link_tf_rate:=-5.0'], '~link_tf_rate'),
    ('contact_sim', ['_rate:=0'], '~rate'),
    ('microphone_sim', ['_chunk_ms:=0.01'], '~chunk_ms'),
    ('microphone_sim', ['_synthetic_f0:=1000'], 'synthetic'),
]


class BadParamsTest(unittest.TestCase):
    def test_bad_parameters_are_fatal_and_named(self):
        for i, (node, args, needle) in enumerate(CASES):
            p = subprocess.run(['rosrun', 'saras_simulation', node, '__name:=bad_%d' % i] + args,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
            out = p.stdout.decode('utf-8', 'replace')
            self.assertEqual(p.returncode, 2, '%s %s: exit %d\n%s' % (node, args, p.returncode, out))
            self.assertIn(needle, out, '%s %s: message does not name %s:\n%s' % (node, args, needle, out))


if __name__ == '__main__':
    rospy.init_node('bad_params_check')
    rostest.rosrun('saras_simulation', 'bad_params', BadParamsTest, sys.argv)
