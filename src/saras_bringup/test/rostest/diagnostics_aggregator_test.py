#!/usr/bin/env python3
"""rostest: the platform's diagnostic_aggregator configuration groups every component.

Two publishers (fake_diagnostics.py) send statuses named like the platform's nodes (product nodes
and simulators); the real bag_recorder is started as node "recorder" and reports through
diagnostic_updater. The aggregator runs with config/diagnostics_aggregator.yaml (launch/
diagnostics.launch). Checked on /diagnostics_agg: each status lands under exactly one group, the
expected one (a stand-in never under the product group it imitates, an unknown node under Other),
and a group's level is the worst of its members. The aggregator shows a status named
"ns/node: task" as "<group>/ns node: task" (slashes of the name become spaces).
"""
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

# status name -> aggregator group path
EXPECTED = {
    'touchball_receiver: link': '/Console link',
    'mesa_left/saras_arms_driver: link': '/SARAS arms/Left',
    'mesa_left/saras_arms_state: state': '/SARAS arms/Left',
    'mesa_right/saras_arms_driver: link': '/SARAS arms/Right',
    'mesa_right/saras_arms_state: state': '/SARAS arms/Right',
    'dvrk/dvrk_sim: PSM1': '/dVRK',
    'endoscope/endoscope_sim: stream': '/Endoscope',
    'teleop/left/velocity_integrator: integrator': '/Teleoperation',
    'teleop/tank_slave/tank_slave: tank': '/Teleoperation',
    'colliding_regions: scene': '/Collision',
    'visual_feedback: overlay': '/Visual feedback',
    'mesa_right/contact_forces: forces': '/Visual feedback',
    'audio/microphone: audio': '/Audio',
    'touchball_console_sim: sender': '/Simulation',
    'mesa_left/saras_arm_sim: server': '/Simulation',
    'contact_sim: contact': '/Simulation',
    'recorder: bag': '/Recording',
    'clock_monitor: teleop_pc': '/Clocks',
    'netem_relay: teleop_link forward': '/Network impairment (test relays)',
    'unknown_node: thing': '/Other',
}


def shown(name):
    """The name the aggregator gives a status under its group."""
    return name.replace('/', ' ')


TIMEOUT = 40.0                        # [s] generous: aggregator, recorder and publishers start


class DiagnosticsAggregator(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix='diagnostics_test_')
        cls.recorder = subprocess.Popen(
            ['rosrun', 'saras_bringup', 'bag_recorder', '-O', os.path.join(cls.tmp, 'diag.bag'),
             '/diagnostics_test/none', '__name:=recorder'],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        cls.cond = threading.Condition()
        cls.latest = None
        rospy.Subscriber('/diagnostics_agg', DiagnosticArray, cls._cb, queue_size=5)

    @classmethod
    def tearDownClass(cls):
        cls.recorder.send_signal(signal.SIGINT)
        try:
            cls.recorder.wait(10)
        except subprocess.TimeoutExpired:
            cls.recorder.kill()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    @classmethod
    def _cb(cls, msg):
        with cls.cond:
            cls.latest = {s.name: s for s in msg.status}
            cls.cond.notify_all()

    def _wait_all(self):
        """The first /diagnostics_agg message that holds every expected status (or the last one)."""
        deadline = rospy.get_time() + TIMEOUT
        with self.cond:
            while not rospy.is_shutdown() and rospy.get_time() < deadline:
                if self.latest and all(any(n.endswith('/' + shown(name)) for n in self.latest) for name in EXPECTED):
                    return self.latest
                self.cond.wait(0.5)
            return self.latest or {}

    def test_every_status_lands_in_its_group_once(self):
        agg = self._wait_all()
        self.assertTrue(agg, 'no /diagnostics_agg message')
        for name, group in EXPECTED.items():
            paths = [n for n in agg if n.endswith('/' + shown(name))]
            self.assertEqual(paths, [group + '/' + shown(name)],
                             '%s: expected under %s, found %s' % (name, group, paths or 'nowhere'))

    def test_group_level_is_the_worst_member(self):
        agg = self._wait_all()
        self.assertIn('/dVRK', agg)
        self.assertEqual(agg['/dVRK'].level, DiagnosticStatus.WARN)   # dvrk_sim: PSM1 is WARN (.test)
        self.assertEqual(agg['/Collision'].level, DiagnosticStatus.OK)

    def test_recorder_reports_its_counters(self):
        agg = self._wait_all()
        rec = agg.get('/Recording/recorder: bag')
        self.assertIsNotNone(rec, 'the recorder status is missing')
        self.assertEqual(rec.hardware_id, 'recording')
        keys = {kv.key for kv in rec.values}
        for k in ('messages received', 'messages dropped (buffer full)', 'write errors'):
            self.assertIn(k, keys)


if __name__ == '__main__':
    rospy.init_node('diagnostics_aggregator_test')
    rostest.rosrun('saras_bringup', 'diagnostics_aggregator', DiagnosticsAggregator)
