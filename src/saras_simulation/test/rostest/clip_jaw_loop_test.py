#!/usr/bin/env python3
"""rostest clip_jaw_loop: the Simball clip opens and closes the simulated instrument jaw through the
whole platform path (console simulator -> UDP -> receiver -> teleoperation -> driver -> arm
simulator -> measured joint_states).

Checks, for every clip step seen on /touchball/left/state (scripted: closed 4 s, open 4 s):
the measured jaw starts moving toward the new clip position (the latency, printed: clip step ->
measured jaw 5 mrad away from where it was), reaches the mapped target (clip 1 rad -> jaw 1 rad;
closed -> 0), and opens no faster than the teleoperation's jaw speed limit allows (10-90 % time;
the simulator's own jaw limit is twice as fast). Margins hold on a busy 2-core host: only a
generous latency bound is asserted."""
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
from saras_msgs.msg import HapticDeviceState
from sensor_msgs.msg import JointState

JOINT = 'mesa_left/jaw'
EDGES = 3              # clip steps to observe (open, close, open)
MAX_LATENCY = 1.0      # [s] generous bound (typical: tens of ms)


class ClipJawLoop(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.clip = []     # (monotonic receive time, clip angle)
        self.jaw = []      # (monotonic receive time, measured jaw)
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, self.on_state, queue_size=2000)
        rospy.Subscriber('/mesa_left/joint_states', JointState, self.on_joints, queue_size=1000)

    def on_state(self, m):
        if not m.stale:
            with self.lock:
                self.clip.append((time.monotonic(), m.clip_angle))

    def on_joints(self, m):
        if JOINT in m.name:
            with self.lock:
                self.jaw.append((time.monotonic(), m.position[m.name.index(JOINT)]))

    def edges(self):
        """Clip steps (time, new clip angle) from the first one at which the jaw had settled on the
        previous clip position (the teleoperation was following, not still starting up)."""
        with self.lock:
            c = list(self.clip)
        steps = [(t1, v0, v1) for (_, v0), (t1, v1) in zip(c, c[1:]) if abs(v1 - v0) > 0.5]
        for i, (t, v0, _) in enumerate(steps):
            before = self.jaw_between(t - 0.5, t)
            if before and abs(before[-1][1] - min(max(v0, 0.0), 1.0)) < 0.02:
                return [(t, v1) for t, _, v1 in steps[i:]]
        return []

    def jaw_between(self, t0, t1):
        with self.lock:
            return [(t, v) for t, v in self.jaw if t0 <= t <= t1]

    def test_clip_opens_and_closes_the_jaw(self):
        deadline = time.monotonic() + 100.0
        while not rospy.is_shutdown() and time.monotonic() < deadline:
            e = self.edges()
            if len(e) > EDGES and e[EDGES][0] + 0.2 < time.monotonic():
                break
            time.sleep(0.2)
        e = self.edges()
        with self.lock:
            n_clip, n_jaw = len(self.clip), len(self.jaw)
        self.assertGreater(len(e), EDGES, 'saw %d clip steps (%d states, %d joint_states)' % (len(e), n_clip, n_jaw))
        vmax = rospy.get_param('~max_jaw_velocity')
        latencies = []
        for (t_edge, clip), (t_next, _) in zip(e[:EDGES], e[1:EDGES + 1]):
            target = min(max(clip, 0.0), 1.0)
            before = self.jaw_between(t_edge - 0.5, t_edge)
            after = self.jaw_between(t_edge, t_next)
            self.assertTrue(before and after, 'no measured jaw around the clip step at %.2f' % t_edge)
            start = before[-1][1]
            moved = [t for t, v in after if abs(v - start) > 0.005 and abs(v - target) < abs(start - target)]
            self.assertTrue(moved, 'jaw did not move after the clip step to %.2f rad (stayed at %.3f)' % (clip, start))
            latencies.append(moved[0] - t_edge)
            final = after[-1][1]
            self.assertAlmostEqual(final, target, delta=0.02,
                                   msg='jaw %.3f rad before the next step, target %.3f' % (final, target))
            # 10 %-90 % of the swing: not faster than the teleoperation's limit (sim limit: 2x)
            span = target - start
            t10 = next(t for t, v in after if (v - start) / span >= 0.1)
            t90 = next(t for t, v in after if (v - start) / span >= 0.9)
            speed = 0.8 * abs(span) / max(t90 - t10, 1e-6)
            print('clip step to %.2f rad: jaw %.3f -> %.3f rad, latency %.1f ms, 10-90 %% speed %.2f rad/s'
                  % (clip, start, final, 1e3 * latencies[-1], speed))
            self.assertLess(speed, 1.3 * vmax, 'jaw faster than max_jaw_velocity %.2f rad/s' % vmax)
        print('clip -> measured jaw latency: min %.1f ms, max %.1f ms over %d steps'
              % (1e3 * min(latencies), 1e3 * max(latencies), len(latencies)))
        self.assertLess(max(latencies), MAX_LATENCY)


if __name__ == '__main__':
    rospy.init_node('clip_jaw_loop_test')
    rostest.rosrun('saras_simulation', 'clip_jaw_loop', ClipJawLoop, sys.argv)
