#!/usr/bin/env python3
"""rostest checker: a bad start-up parameter makes the node exit non-zero naming the parameter
(contact_forces and VisualFeedback under `nodelet standalone`), a good one keeps it running."""
import os
import subprocess
import sys
import unittest

import rospy
import rostest


def run(executable, args, timeout=15.0):
    """Runs a node of this package ('visual_feedback': the nodelet through `nodelet standalone`);
    returns (exit code or None if still running, output)."""
    if executable == 'visual_feedback':
        cmd = ['rosrun', 'nodelet', 'nodelet', 'standalone', 'saras_visual_feedback/VisualFeedback'] + args
    else:
        cmd = ['rosrun', 'saras_visual_feedback', executable] + args
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=os.environ.copy())
    try:
        out, _ = p.communicate(timeout=timeout)
        return p.returncode, out.decode(errors='replace')
    except subprocess.TimeoutExpired:
        p.terminate()
        try:
            out, _ = p.communicate(timeout=5.0)
        except subprocess.TimeoutExpired:
            p.kill()
            out, _ = p.communicate()
        return None, out.decode(errors='replace')


class TestBadParams(unittest.TestCase):
    def test_contact_forces_rejects_bad_k_skin(self):
        code, out = run('contact_forces', ['__name:=cf_bad', '_k_skin:=-3.0'])
        self.assertIsNotNone(code, 'node kept running with k_skin = -3')
        self.assertNotEqual(code, 0)
        self.assertIn('k_skin', out)

    def test_contact_forces_rejects_bad_rate(self):
        code, out = run('contact_forces', ['__name:=cf_bad_rate', '_rate:=0.0'])
        self.assertNotEqual(code, 0)
        self.assertIsNotNone(code)
        self.assertIn('~rate', out)

    def test_contact_forces_runs_with_good_params(self):
        code, _ = run('contact_forces', ['__name:=cf_good', '_k_skin:=300.0'], timeout=3.0)
        self.assertIsNone(code, 'node exited with valid parameters')

    def test_visual_feedback_rejects_bad_thresholds(self):
        code, out = run('visual_feedback', ['__name:=vf_bad', '_collision_threshold:=0.03',
                                                 '_warning_threshold:=0.02'])
        self.assertIsNotNone(code, 'node kept running with warning_threshold < collision_threshold')
        self.assertNotEqual(code, 0)
        self.assertIn('warning_threshold', out)

    def test_visual_feedback_rejects_bad_colour(self):
        code, out = run('visual_feedback', ['__name:=vf_bad_colour', '_safe_colour:=green'])
        self.assertNotEqual(code, 0)
        self.assertIsNotNone(code)
        self.assertIn('safe_colour', out)

    def test_visual_feedback_rejects_bad_pose_history(self):
        code, out = run('visual_feedback', ['__name:=vf_bad_history', '_pose_buffer_size:=1'])
        self.assertIsNotNone(code, 'node kept running with pose_buffer_size = 1')
        self.assertNotEqual(code, 0)
        self.assertIn('pose_buffer_size', out)
        code, out = run('visual_feedback', ['__name:=vf_bad_tolerance', '_pose_stamp_tolerance:=-0.1'])
        self.assertIsNotNone(code, 'node kept running with pose_stamp_tolerance < 0')
        self.assertNotEqual(code, 0)
        self.assertIn('pose_stamp_tolerance', out)


if __name__ == '__main__':
    rospy.init_node('check_bad_params', anonymous=True)
    rostest.rosrun('saras_visual_feedback', 'check_bad_params', TestBadParams, sys.argv)
