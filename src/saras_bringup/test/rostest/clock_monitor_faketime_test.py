#!/usr/bin/env python3
"""rostest: the clock monitor measures libfaketime offsets within 1 ms and warns above 2 ms.

clock_monitor_faketime.test runs four clock responders, three of them under libfaketime with their
wall clocks offset by +5, +50 and -80 ms. The monitor's /diagnostics statuses (hardware_id
`clocks`) must report every offset within 1 ms of the one set, WARN for the three faked clocks and
OK for the unfaked one, from a full window of exchanges.
"""
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

EXPECTED_MS = {'core_pc': 0.0, 'plus_5ms': 5.0, 'plus_50ms': 50.0, 'minus_80ms': -80.0}
TOLERANCE_MS = 1.0
WINDOW = 16


class ClockMonitorFaketime(unittest.TestCase):
    def setUp(self):
        self.latest = {}
        self.lock = threading.Lock()
        self.sub = rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics)

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                if status.name.startswith('clock_monitor: '):
                    self.latest[status.name[len('clock_monitor: '):]] = status

    def settled(self):
        with self.lock:
            statuses = dict(self.latest)
        if set(statuses) != set(EXPECTED_MS):
            return None
        for status in statuses.values():
            values = {kv.key: kv.value for kv in status.values}
            if int(values.get('samples', 0)) < WINDOW:
                return None
        return statuses

    def test_offsets_and_warnings(self):
        deadline = time.monotonic() + 60.0
        statuses = None
        while statuses is None and time.monotonic() < deadline:
            time.sleep(0.25)
            statuses = self.settled()
        with self.lock:
            seen = {m: (s.level, s.message) for m, s in self.latest.items()}
        self.assertIsNotNone(statuses, 'no full window for every machine: %s' % seen)
        for machine, expected in EXPECTED_MS.items():
            status = statuses[machine]
            values = {kv.key: kv.value for kv in status.values}
            offset = float(values['offset_ms'])
            rospy.loginfo('%s: offset %.3f ms (set %.1f), round trip %s ms, level %d', machine,
                          offset, expected, values['round_trip_ms'], status.level)
            self.assertEqual(status.hardware_id, 'clocks')
            self.assertLessEqual(abs(offset - expected), TOLERANCE_MS,
                                 '%s: %.3f ms measured, %.1f ms set' % (machine, offset, expected))
            level = DiagnosticStatus.OK if expected == 0.0 else DiagnosticStatus.WARN
            self.assertEqual(status.level, level, '%s: %s' % (machine, status.message))


if __name__ == '__main__':
    rospy.init_node('clock_monitor_faketime_test')
    rostest.rosrun('saras_bringup', 'clock_monitor_faketime', ClockMonitorFaketime)
