#!/usr/bin/env python3
"""Closed-loop rostest of the real teleop nodes with a fake master (TF touch_left/stylus moving on a
sinusoid) and a fake SARAS arm (ee_pose = last target_pose). Checks tracking of the scaled master in
the slave base frame, the force command, tank energies, bad-input robustness, the stale-link hold
(resumed only through the operator's clutch, from the held pose), the contact-force gate (1e6 N
holds the arm) and the degradation when collision monitoring (/collision/report) goes silent.
Parameters (~): expect_delay [s] (one-way channel delay configured in the .test), check_stale (bool),
expect_manager (nodelet manager that must hold every teleop nodelet; '' = do not check)."""
import math
import os
import subprocess
import sys
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, TransformStamped, Twist, WrenchStamped
from saras_msgs.msg import CollisionReport, ComponentStatus, HapticDeviceState
from std_msgs.msg import Bool, Float64

from node_util import node_pid

AMP = 0.02    # master stroke along touch_left/base x [m]
FREQ = 0.25   # [Hz]
SCALE = 0.5   # transparency scale_factor (config/transparency.yaml)


# world_frames.yaml of saras_bringup (parent, child, xyz, yaw about z)
STATIC_FRAMES = [
    ('world', 'mesa_left/sbs_world', (0.0, 0.45, 0.0), -math.pi / 2),
    ('world', 'mesa_right/sbs_world', (0.0, -0.45, 0.0), math.pi / 2),
    ('world', 'console', (-1.2, 0.0, 0.8), 0.0),
    ('console', 'touch_left/base', (0.0, 0.2, 0.0), 0.0),
    ('console', 'touch_right/base', (0.0, -0.2, 0.0), 0.0),
]


# a stand-in arm driver, run in its own process: latched arm_link true, subscribed to the set-points
FAKE_DRIVER = """
import rospy
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Bool
rospy.init_node('fake_arms_driver', disable_signals=True)
pub = rospy.Publisher('/mesa_left/arm_link', Bool, queue_size=1, latch=True)
pub.publish(Bool(data=True))
rospy.Subscriber('/mesa_left/target_pose', PoseStamped, lambda m: None, tcp_nodelay=True)
print('ready', flush=True)
rospy.spin()
"""


class Fixture(object):
    @staticmethod
    def static(parent, child, xyz, yaw):
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = parent
        t.child_frame_id = child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
        t.transform.rotation.z = math.sin(yaw / 2)
        t.transform.rotation.w = math.cos(yaw / 2)
        return t

    def __init__(self):
        self.lock = threading.Lock()
        self.targets = []          # (receive time, stamp, x, y, z)
        self.wrenches = []
        self.energy = {'master': [], 'slave': []}
        self.status = []
        self.ee = None
        self.master_log = []       # (time, x in touch base)
        self.stale = False
        self.nan_stylus = False
        self.collision = True      # publish /collision/report (collision monitoring alive)
        self.br = tf2_ros.TransformBroadcaster()
        self.static_br = tf2_ros.StaticTransformBroadcaster()
        self.static_br.sendTransform([self.static(*f) for f in STATIC_FRAMES])
        self.ee_pub = rospy.Publisher('/mesa_left/ee_pose', PoseStamped, queue_size=10, tcp_nodelay=True)
        self.status_pub = rospy.Publisher('/touchball/status', ComponentStatus, queue_size=10)
        self.force_pub = rospy.Publisher('/mesa_left/contact_force', Twist, queue_size=10)
        self.tank_pub = rospy.Publisher('/teleop/left/tank_wrench', WrenchStamped, queue_size=10)
        self.device_pub = rospy.Publisher('/touchball/left/state', HapticDeviceState, queue_size=10)
        self.collision_pub = rospy.Publisher('/collision/report', CollisionReport, queue_size=10)
        rospy.Subscriber('/mesa_left/target_pose', PoseStamped, self.on_target, tcp_nodelay=True)
        rospy.Subscriber('/touchball/left/wrench_cmd', WrenchStamped, self.on_wrench, tcp_nodelay=True)
        rospy.Subscriber('/teleop/tank_master/energy', Float64, lambda m: self.on_energy('master', m))
        rospy.Subscriber('/teleop/tank_slave/energy', Float64, lambda m: self.on_energy('slave', m))
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics)
        self.holds = []            # (time, data) of /mesa_left/hold (the arm driver stops the arm on true)
        rospy.Subscriber('/mesa_left/hold', Bool, lambda m: self.holds.append((time.time(), m.data)))
        self.arm_link_pub = rospy.Publisher('/mesa_left/arm_link', Bool, queue_size=2, latch=True)
        self.start_pose = PoseStamped()
        self.start_pose.header.frame_id = 'mesa_left/sbs_world'
        self.start_pose.pose.position.x, self.start_pose.pose.position.y, self.start_pose.pose.position.z = 0.3, 0.1, 0.15
        self.start_pose.pose.orientation.w = 1.0
        self.t0 = time.time()
        self.run = True
        threading.Thread(target=self.master_loop, daemon=True).start()
        threading.Thread(target=self.arm_loop, daemon=True).start()

    def on_target(self, m):
        with self.lock:
            self.targets.append((time.time(), m.header.stamp.to_sec(), m.pose.position.x, m.pose.position.y,
                                 m.pose.position.z, m.header.frame_id))
            self.ee = m

    def on_wrench(self, m):
        with self.lock:
            self.wrenches.append((m.header.frame_id, m.wrench.force.x, m.wrench.force.y, m.wrench.force.z))

    def on_energy(self, side, m):
        with self.lock:
            self.energy[side].append(m.data)

    def on_diagnostics(self, m):
        """(status name, level, hardware_id, key/values) of every status on /diagnostics."""
        with self.lock:
            for s in m.status:
                self.status.append((s.name, s.level, s.hardware_id, {kv.key: kv.value for kv in s.values}))

    def master_x(self, t):
        return AMP * math.sin(2 * math.pi * FREQ * t)

    def master_loop(self):
        r = rospy.Rate(500)
        while self.run and not rospy.is_shutdown():
            t = time.time() - self.t0
            x = self.master_x(t)
            ts = TransformStamped()
            ts.header.stamp = rospy.Time.now()
            ts.header.frame_id = 'touch_left/base'
            ts.child_frame_id = 'touch_left/stylus'
            ts.transform.translation.x = float('nan') if self.nan_stylus else x
            ts.transform.translation.y = 0.01
            ts.transform.translation.z = 0.05
            ts.transform.rotation.w = 1.0
            self.br.sendTransform(ts)
            with self.lock:
                self.master_log.append((time.time(), x))
            r.sleep()

    def arm_loop(self):
        r = rospy.Rate(250)
        k = 0
        while self.run and not rospy.is_shutdown():
            with self.lock:
                m = self.ee if self.ee is not None else self.start_pose
            out = PoseStamped()
            out.header.stamp = rospy.Time.now()
            out.header.frame_id = 'mesa_left/sbs_world'
            out.pose = m.pose
            self.ee_pub.publish(out)
            k += 1
            if k % 25 == 0:
                st = ComponentStatus()
                st.header.stamp = rospy.Time.now()
                st.component = 'touchball_receiver'
                st.level = ComponentStatus.STALE if self.stale else ComponentStatus.OK
                self.status_pub.publish(st)
            if k % 12 == 0 and self.collision:
                self.collision_pub.publish(CollisionReport())
            r.sleep()

    def clutch(self):
        """The operator presses the clutch for 0.2 s and releases it; returns the release time."""
        for pressed in (True, False):
            m = HapticDeviceState()
            m.device = 'left'
            m.clutch = pressed
            for _ in range(10):
                m.header.stamp = rospy.Time.now()
                self.device_pub.publish(m)
                time.sleep(0.02)
            if pressed:
                release = time.time()
        return release


class TeleopLoopTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('teleop_loop_test')
        cls.fx = Fixture()
        cls.delay = rospy.get_param('~expect_delay', 0.0)

    def wait_for(self, cond, timeout, what):
        end = time.time() + timeout
        while time.time() < end and not rospy.is_shutdown():
            if cond():
                return
            time.sleep(0.05)
        self.fail('timed out waiting for ' + what)

    def test_loop(self):
        fx = self.fx
        self.wait_for(lambda: len(fx.targets) > 100, 30.0, '/mesa_left/target_pose')
        time.sleep(8.0)  # two master periods
        with fx.lock:
            targets = list(fx.targets)
            master = list(fx.master_log)
            wrenches = list(fx.wrenches)
            e_m = list(fx.energy['master'])
            e_s = list(fx.energy['slave'])
        # set-points: frame, rate, finite
        self.assertEqual(targets[-1][5], 'mesa_left/sbs_world')
        span = targets[-1][0] - targets[-1000][0]
        rate = 999.0 / span
        rospy.loginfo('target_pose rate %.0f Hz', rate)
        # the set-point follows each master sample (500 Hz here) and is republished after 1.5 ms
        # without one; rospy on a loaded 2-core machine is no rate meter (bench/run measures it)
        self.assertGreater(rate, 400.0)
        # tracking: the slave base is rotated -90 deg about z with respect to the console, so master +x
        # (touch base) is slave +y; the set-point displacement is SCALE * master displacement, delayed
        x0, y0 = targets[0][3], targets[0][2]
        tm = [m[0] for m in master]
        errs = []
        import bisect
        m_first = master[bisect.bisect_left(tm, targets[0][0] - self.delay)][1]
        for (tr, _, x, y, z, _f) in targets[-4000:]:
            i = bisect.bisect_left(tm, tr - self.delay) - 1
            if i <= 0:
                continue
            expected = SCALE * (master[i][1] - m_first)
            errs.append((y - x0) - expected)  # slave y follows master x
        errs = errs[len(errs) // 4:]
        mean = sum(errs) / len(errs)   # constant offset = where the integration started: legitimate
        rms = math.sqrt(sum((e - mean) ** 2 for e in errs) / len(errs))
        span_y = max(t[3] for t in targets[-4000:]) - min(t[3] for t in targets[-4000:])
        rospy.loginfo('tracking rms %.2f mm over a %.1f mm stroke', rms * 1e3, span_y * 1e3)
        # it moved with the master (velocity integration: gaps > max_step in this Python-driven master
        # stream are not integrated, so a few % of stroke can be lost on a loaded machine)
        self.assertGreater(span_y, 0.7 * 2 * SCALE * AMP)
        self.assertLess(span_y, 1.1 * 2 * SCALE * AMP)
        self.assertLess(rms, 0.004)                          # within 4 mm incl. ROS timing (offset-free)
        # force command: in the device frame, finite and within the device limit
        self.assertGreater(len(wrenches), 1000)
        self.assertEqual(wrenches[-1][0], 'touch_left/base')
        for w in wrenches[-1000:]:
            n = math.sqrt(w[1] ** 2 + w[2] ** 2 + w[3] ** 2)
            self.assertTrue(math.isfinite(n) and n <= 3.3 + 1e-6)
        # tanks: published, within bounds
        self.assertGreater(len(e_m), 1000)
        self.assertGreater(len(e_s), 1000)
        self.assertTrue(all(1.0 <= e <= 20.0 for e in e_m + e_s))

        # bad input: NaN contact force, NaN tank wrench, NaN master pose -> nodes survive, counters rise
        nan = float('nan')
        tw = Twist()
        tw.linear.x = nan
        fx.force_pub.publish(tw)
        w = WrenchStamped()
        w.wrench.force.x = nan
        fx.tank_pub.publish(w)
        fx.nan_stylus = True
        time.sleep(0.5)
        fx.nan_stylus = False
        time.sleep(1.5)
        with fx.lock:
            last = list(fx.targets[-200:])
            status = list(fx.status)
        self.assertTrue(all(math.isfinite(t[2]) and math.isfinite(t[3]) for t in last))
        # health on /diagnostics: one status per teleop node ("<node name>: <task>"), hardware_id
        # teleoperation, the counters of rejected input among its key/values
        teleop = [s for s in status if s[2] == 'teleoperation']
        names = {s[0] for s in teleop}
        for expected in ('teleop/tank_master/tank_master: energy tank', 'teleop/tank_slave/tank_slave: energy tank',
                         'teleop/transparency: transparency', 'teleop/left/tf_transformer: master tracking',
                         'teleop/left/velocity_integrator: set-point'):
            self.assertIn(expected, names)
        rejected = {}
        for name, _lvl, _hw, values in teleop:
            if 'rejected' in values:
                rejected[name] = max(rejected.get(name, 0), int(values['rejected']))
        rospy.loginfo('rejected counters: %s', rejected)
        self.assertGreater(rejected.get('teleop/tank_slave/tank_slave: energy tank', 0), 0)
        self.assertGreater(rejected.get('teleop/left/tf_transformer: master tracking', 0), 0)
        energies = [float(v['energy [J]']) for n, _l, _h, v in teleop if n.endswith('energy tank') and 'energy [J]' in v]
        self.assertTrue(energies and all(1.0 <= e <= 20.0 for e in energies), energies)
        rates = [float(v['target_pose rate [Hz]']) for n, _l, _h, v in teleop
                 if n == 'teleop/left/velocity_integrator: set-point' and 'target_pose rate [Hz]' in v]
        self.assertGreater(max(rates), 100.0)  # the set-point stream, as counted by the node

        # stale master link: the set-point holds although the master keeps moving
        fx.stale = True
        time.sleep(0.5)
        with fx.lock:
            n0 = len(fx.targets)
        time.sleep(2.0)
        with fx.lock:
            held = list(fx.targets[n0:])
        self.assertGreater(len(held), 1000)   # still published at rate
        ys = [t[3] for t in held]
        self.assertLess(max(ys) - min(ys), 1e-9)
        self.assertTrue(fx.holds and fx.holds[-1][1], 'hold not published while the link is stale: %s' % fx.holds)
        n_before = len(fx.holds)
        fx.clutch()                                   # a clutch while the link is still stale: still held
        time.sleep(0.5)
        self.assertTrue(all(h for _, h in fx.holds[n_before:]),
                        'a clutch while the console link was stale released the hold: %s' % fx.holds[n_before:])
        fx.stale = False
        time.sleep(1.5)
        self.assertTrue(fx.holds[-1][1], 'the hold ended without the clutch')
        with fx.lock:
            still = [t[2:5] for t in fx.targets[n0:]]
        # link back, but no clutch yet: still held (resumes only through the operator's clutch)
        self.assertLess(max(abs(p[1] - still[0][1]) for p in still), 1e-9)
        held = still[-1]
        release = fx.clutch()
        time.sleep(2.0)
        with fx.lock:
            after = [t[2:5] for t in fx.targets if t[0] > release]
        self.assertGreater(max(p[1] for p in after) - min(p[1] for p in after), 1e-3)  # resumed
        self.assertFalse(fx.holds[-1][1], 'hold still true after the clutch release')
        n_holds = len(fx.holds)
        fx.clutch()                                   # a plain clutch press (no fault): no hold
        time.sleep(0.3)
        self.assertFalse(any(h for _, h in fx.holds[n_holds:]), 'a plain clutch press raised the hold')
        first = after[0]
        self.assertLess(math.dist(first, held), 1e-3)  # first set-point after recovery: the held pose
        steps = [math.dist(a, b) for a, b in zip(after, after[1:])]
        self.assertLess(max(steps), 1e-3)            # no jump on the way

        # contact force of 1e6 N (spoofed or faulty): the set-point does not move while it lasts
        tw = Twist()
        tw.linear.z = 1e6
        with fx.lock:
            n1 = len(fx.targets)
        end = time.time() + 2.0
        while time.time() < end:
            fx.force_pub.publish(tw)
            time.sleep(1.0 / 60)
        with fx.lock:
            spoofed = [t[2:5] for t in fx.targets[n1 + 50:]]  # from 0.2 s in (gate reaction + queue)
        self.assertGreater(len(spoofed), 100)
        self.assertLess(max(math.dist(p, spoofed[0]) for p in spoofed), 2e-4)
        time.sleep(1.0)
        with fx.lock:
            gate = [(l, v) for n, l, _h, v in fx.status if n == 'teleop/tank_slave/tank_slave: energy tank'
                    and int(v.get('contact force violations', '0')) > 0]
        self.assertTrue(gate, 'contact-force violations not reported on /diagnostics')
        # the gate (tank_slave's force_gate) holds the chain: the driver stops the arm where it is
        self.assertTrue(fx.holds[-1][1], 'no hold on the implausible contact force: %s' % fx.holds[-3:])
        fx.clutch()
        self.wait_for(lambda: not fx.holds[-1][1], 2.0, 'the hold to end at the clutch release')

        self.check_arm_link(fx)

        # collision monitoring gone: reported, and the set-point slows to 20 % of the limit
        fx.collision = False
        time.sleep(1.5)
        with fx.lock:
            lost = [v for n, l, _h, v in fx.status[-200:] if n == 'teleop/left/velocity_integrator: set-point'
                    and v.get('collision monitoring') == 'lost']
        self.assertTrue(lost, 'loss of collision monitoring not reported on /diagnostics')
        fx.run = False

    def check_arm_link(self, fx):
        """The arm driver restarted (arm_link false, then true): the set-point holds until the operator's
        clutch after the link is back (a clutch while it is down does not resume), then re-anchors."""
        fx.arm_link_pub.publish(Bool(data=False))
        self.wait_for(lambda: fx.holds and fx.holds[-1][1], 2.0, 'the hold on arm_link false')
        t_hold = fx.holds[-1][0]
        fx.clutch()
        time.sleep(0.5)
        self.assertTrue(fx.holds[-1][1], 'a clutch while the arm link was down released the hold')
        fx.arm_link_pub.publish(Bool(data=True))
        time.sleep(0.5)
        self.assertTrue(fx.holds[-1][1], 'the hold ended with the arm link, without the clutch')
        release = fx.clutch()
        with fx.lock:
            frozen = [t[2:5] for t in fx.targets if t_hold + 0.1 < t[0] < release - 0.3]
        self.assertGreater(len(frozen), 100)
        self.assertLess(max(math.dist(p, frozen[0]) for p in frozen), 1e-9)
        time.sleep(1.5)
        self.assertFalse(fx.holds[-1][1], 'hold still true after the clutch release with the arm link up')
        with fx.lock:
            after = [t[2:5] for t in fx.targets if t[0] > release]
        self.assertGreater(max(p[1] for p in after) - min(p[1] for p in after), 1e-3)  # resumed
        self.assertLess(math.dist(after[0], frozen[-1]), 1e-3)
        self.check_driver_killed(fx)

    def check_driver_killed(self, fx):
        """A stand-in arm driver (its own process: publishes arm_link, subscribes to the set-points) is
        SIGKILLed, so nothing unregisters: the velocity integrator sees its subscription drop and holds."""
        driver = subprocess.Popen([sys.executable, '-c', FAKE_DRIVER], stdout=subprocess.PIPE, text=True)
        try:
            self.assertEqual(driver.stdout.readline().strip(), 'ready')
            time.sleep(1.5)                                   # the integrator connected to it
            self.assertFalse(fx.holds[-1][1], 'hold before the driver died')
            driver.kill()
            self.wait_for(lambda: fx.holds[-1][1], 2.0, 'the hold when the arm driver process is killed')
        finally:
            driver.kill()
            driver.wait()
        fx.arm_link_pub.publish(Bool(data=True))              # a driver again
        time.sleep(0.5)
        self.assertTrue(fx.holds[-1][1], 'the hold ended with a new driver, without the clutch')
        fx.clutch()
        self.wait_for(lambda: not fx.holds[-1][1], 2.0, 'the hold to end at the clutch with a driver back')

    def test_nodelets_share_one_manager(self):
        """Every teleop output is published by the manager process (the nodelets run inside it: their
        intra-process links are zero-copy), none by the nodelet loader processes."""
        manager = rospy.get_param('~expect_manager', '')
        if not manager:
            self.skipTest('standalone layout: no manager expected')
        import rosgraph
        topics = ['/teleop/left/master_pose', '/teleop/left/master_twist', '/teleop/left/des_twist',
                  '/teleop/left/des_wrench', '/teleop/left/tank_twist', '/teleop/left/tank_wrench',
                  '/mesa_left/target_pose', '/touchball/left/wrench_cmd', '/teleop/right/master_pose',
                  '/teleop/tank_master/energy', '/teleop/tank_slave/energy']
        if self.delay > 0:
            topics.append('/teleop/left/master_pose_delayed')
        master = rosgraph.Master('/teleop_loop_test')
        pubs = {}
        end = time.time() + 20.0
        while time.time() < end:
            pubs = {t: sorted(set(n) - {rospy.get_name()}) for t, n in master.getSystemState()[0]}
            if all(t in pubs for t in topics):
                break
            time.sleep(0.5)
        for t in topics:
            self.assertEqual(pubs.get(t), [manager], t)

    def test_callback_thread(self):
        """teleop.launch callback_thread: with `shared` the teleop nodes' callbacks run on the nodelet
        manager's main thread (the global callback queue), so that thread does most of the manager's
        work; with `manager` the worker threads do and the main thread stays nearly idle. Measured from
        the per-thread CPU times in /proc over 3 s while the loop runs."""
        expected = rospy.get_param('~expect_callback_thread', '')
        manager = rospy.get_param('~expect_manager', '')
        if not expected or not manager:
            self.skipTest('no callback thread expectation')
        pid = node_pid(manager)

        def cpu():
            ticks = {}
            for tid in os.listdir('/proc/%d/task' % pid):
                with open('/proc/%d/task/%s/stat' % (pid, tid)) as f:
                    fields = f.read().rsplit(')', 1)[1].split()
                ticks[int(tid)] = int(fields[11]) + int(fields[12])
            return ticks
        a = cpu()
        time.sleep(3.0)
        b = cpu()
        used = {t: b[t] - a.get(t, 0) for t in b}
        total = sum(used.values())
        self.assertGreater(total, 0)
        main_share = used.get(pid, 0) / float(total)
        rospy.loginfo('manager threads CPU ticks over 3 s (main = %d): %s', pid, used)
        # typically shared about 0.4 (the rest: roscpp's TCP poll and timer threads), manager below 0.05
        if expected == 'shared':
            self.assertGreater(main_share, 0.25, used)
        else:
            self.assertLess(main_share, 0.1, used)
        # an unknown value is a startup error naming the parameter
        p = subprocess.run(['rosrun', 'nodelet', 'nodelet', 'standalone', 'saras_teleop/TankMaster', '__name:=bad_thread',
                            '_callback_thread:=own'],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=20)
        self.assertNotEqual(p.returncode, 0)
        self.assertIn('callback_thread', p.stdout.decode(errors='replace'))

    def test_bad_parameter_exits_with_message(self):
        p = subprocess.run(['rosrun', 'nodelet', 'nodelet', 'standalone', 'saras_teleop/TankMaster', '__name:=bad_tank',
                            '_T_req:=0.5'],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=20)
        out = p.stdout.decode(errors='replace')
        self.assertNotEqual(p.returncode, 0)
        self.assertIn('T_req', out)


if __name__ == '__main__':
    rostest.rosrun('saras_teleop', 'teleop_loop_test', TeleopLoopTest, sys.argv)
