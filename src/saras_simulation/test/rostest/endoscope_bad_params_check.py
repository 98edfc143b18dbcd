#!/usr/bin/env python3
"""rostest: the endoscope simulator (`nodelet standalone saras_simulation/EndoscopeSim`) rejects bad
parameters at start-up: the process exits with a non-zero status and a message naming the parameter."""
import os
import subprocess
import sys
import tempfile
import unittest

import rospy
import rostest

CONFIG = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'config')


def cases():
    bad_vertices = os.path.join(tempfile.mkdtemp(), 'bad_vertices.txt')
    with open(bad_vertices, 'w') as f:
        f.write('2\n0 0 0\n')
    info = ['_camera_info_dir:=%s' % CONFIG]
    return [
        (['_fps:=0'], '/fps = 0 [Hz] is invalid'),
        (['_fps:=500'] + info, '/fps = 500'),
        (['_camera_info_dir:=/nonexistent'], 'camera_info'),
        (info + ['_width:=8'], '/width = 8'),
        (info + ['_jpeg_quality:=101'], '/jpeg_quality = 101'),
        (info + ['_bones_file:=%s' % bad_vertices], '/bones_file'),
        (info + ['_bones_file:=%s' % bad_vertices], 'unexpected end of file in box 0'),
        (info + ['_tools:=[{tip: PSM1/tool_tip}]'], '/tools'),
        (info + ['_tissue:={z0: .nan}'], '/tissue'),
        (info + ['_texture_extent:=-1'], '/texture_extent = -1'),
        (info + ['_recorded_queue:=0'], '/recorded_queue = 0'),
    ]


class EndoscopeBadParamsTest(unittest.TestCase):
    def test_bad_parameters_are_fatal_and_named(self):
        for i, (args, needle) in enumerate(cases()):
            p = subprocess.run(['rosrun', 'nodelet', 'nodelet', 'standalone', 'saras_simulation/EndoscopeSim',
                                '__name:=bad_endo_%d' % i] + args,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
            out = p.stdout.decode('utf-8', 'replace')
            self.assertNotEqual(p.returncode, 0, '%s: exit 0\n%s' % (args, out))
            self.assertIn(needle, out, '%s: message does not name %s:\n%s' % (args, needle, out))


if __name__ == '__main__':
    rospy.init_node('endoscope_bad_params_check')
    rostest.rosrun('saras_simulation', 'endoscope_bad_params', EndoscopeBadParamsTest, sys.argv)
