#!/usr/bin/env python3
"""Benchmark: the SARAS arm ROS nodes end to end, alone or on a loaded host (not a test).

Starts a private roscore and, for both arms, ``saras_arm.launch`` (simulator, driver, state node)
plus the arm's robot_state_publisher (``saras_description/robot.launch``, 1 kHz max), streams
``target_pose`` set-points to each driver at ``--target-rate`` (a slow circle around the start
pose, like the teleoperation's velocity integrator) and measures for ``--duration`` seconds:

  * the rate and largest gap of ``/mesa_<side>/ee_pose``, ``joint_states`` and of the arm's TF
    (``mesa_<side>/tool_tip`` in ``/tf``, from robot_state_publisher);
  * the CPU % (of one core, from /proc) of every process of the arm stack;
  * link drops (driver/state node ERROR on ``/diagnostics`` after they were OK) and the
    driver's dropped set-points (its ``rejected``/``dropped`` counters);

optionally with ``--load N`` busy-loop processes (nice 0) competing for the CPUs.
With ``--platform`` the whole simulated platform runs instead (launch/platform.launch rviz:=false
record:=false control_rate:=``--control-rate``, private roscore and ports; the teleoperation chain
commands the arms). Usage:
  saras_arm_ros.py [--duration S] [--load N] [--target-rate HZ] [--publish-tf]
  saras_arm_ros.py --platform [--control-rate HZ] [--duration S]
Needs the workspace built (scripts/env.sh); prints one markdown table.
"""
import argparse
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time

from saras_simulation.bench_util import cpu_seconds, free_port, process_cmdlines, stop_process_groups

SIDES = ('left', 'right')


def arm_processes():
    """{'<ns>/<node>': pid} of the roslaunch'ed arm processes (from their __log:= argument)."""
    out = {}
    for pid, args in process_cmdlines():
        for a in args:
            if a.startswith(b'__log:=') and b'mesa_' in a:
                name = os.path.basename(a[7:].decode()).rsplit('-', 1)[0]   # mesa_left-saras_arm_sim
                out[name.replace('-', '/', 1)] = pid
    return out


LAUNCH = """<launch>
  <include file="$(find saras_description)/launch/robot.launch">
    <arg name="ns" value="mesa_{side}"/>
    <arg name="robot" value="saras_arm"/>
    <arg name="urdf_args" value="--prefix mesa_{side}/ --config $(find saras_description)/config/saras_arms.yaml"/>
    <arg name="joint_states" value="{rsp_js}"/>
    <arg name="publish_frequency" value="1000"/>
  </include>
  <include file="$(find saras_simulation)/launch/saras_arm.launch">
    <arg name="side" value="{side}"/>
    <arg name="port" value="{port}"/>
    <arg name="publish_tf" value="{publish_tf}"/>
  </include>
</launch>
"""


def bag_stats(path, w0, w1):
    """{stream: [messages, largest receive gap, largest header-stamp gap]} in [w0, w1]."""
    import rosbag
    out = {}
    last = {}
    with rosbag.Bag(path) as b:
        for topic, msg, t in b.read_messages(start_time=w0, end_time=w1):
            if topic == '/tf':
                keys = set()
                for tr in msg.transforms:
                    side = tr.child_frame_id.split('/', 1)[0]
                    if side.startswith('mesa_'):
                        keys.add(('/tf (%s/* moving frames)' % side, tr.header.stamp))
            else:
                keys = {(topic, msg.header.stamp)}
            for key, stamp in keys:
                s = out.setdefault(key, [0, 0.0, 0.0])
                if key in last:
                    s[1] = max(s[1], (t - last[key][0]).to_sec())
                    s[2] = max(s[2], (stamp - last[key][1]).to_sec())
                last[key] = (t, stamp)
                s[0] += 1
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--duration', type=float, default=20.0)
    ap.add_argument('--load', type=int, default=0, help='busy-loop processes (nice 0)')
    ap.add_argument('--target-rate', type=float, default=250.0)
    ap.add_argument('--platform', action='store_true',
                    help='measure inside the whole simulated platform (launch/platform.launch '
                         'rviz:=false record:=false, the teleoperation drives the arms)')
    ap.add_argument('--control-rate', type=float, default=250.0, help='--platform: control_rate [Hz]')
    ap.add_argument('--publish-tf', action='store_true',
                    help='TF from saras_arms_state (~publish_tf) instead of robot_state_publisher')
    args, _ = ap.parse_known_args()
    env = dict(os.environ)
    env['ROS_MASTER_URI'] = 'http://127.0.0.1:%d' % free_port()
    env['ROS_HOSTNAME'] = '127.0.0.1'
    os.environ.update(env)
    procs = []
    tmp = tempfile.mkdtemp(prefix='saras_arm_bench_')
    try:
        procs.append(subprocess.Popen(['roscore', '-p', env['ROS_MASTER_URI'].rsplit(':', 1)[1]],
                                      env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
        time.sleep(3.0)
        if args.platform:
            platform = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..',
                                    'launch', 'platform.launch')
            procs.append(subprocess.Popen(
                ['roslaunch', '--wait', platform, 'rviz:=false', 'record:=false', 'operator_view:=false',
                 'control_rate:=%g' % args.control_rate, 'left_arm_port:=%d' % free_port(),
                 'right_arm_port:=%d' % free_port(), 'console_port:=%d' % free_port()],
                env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True))
            return measure(args, procs)
        for side in SIDES:
            path = os.path.join(tmp, 'arm_%s.launch' % side)
            with open(path, 'w') as f:
                f.write(LAUNCH.format(side=side, port=free_port(),
                                      publish_tf='true' if args.publish_tf else 'false',
                                      rsp_js='/mesa_%s/joint_states%s'
                                      % (side, '_unused' if args.publish_tf else '')))
            procs.append(subprocess.Popen(['roslaunch', '--wait', path], env=env,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                          start_new_session=True))
        return measure(args, procs)
    finally:
        stop_process_groups(procs, timeout=15.0)


class ArmWatch(object):
    """The first ee_pose of each arm and the arm components' /diagnostics (level changes,
    rejected counters); the set-point publishers."""

    def __init__(self):
        import rospy
        from geometry_msgs.msg import PoseStamped
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
        self.OK, self.ERROR = DiagnosticStatus.OK, DiagnosticStatus.ERROR
        self.start, self.status, self.pubs, self.subs = {}, {}, {}, []
        for side in SIDES:
            self.subs.append(rospy.Subscriber('/mesa_%s/ee_pose' % side, PoseStamped, self.on_pose, side,
                                              queue_size=1))
            self.pubs[side] = rospy.Publisher('/mesa_%s/target_pose' % side, PoseStamped, queue_size=1,
                                              tcp_nodelay=True)
        self.subs.append(rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=100))

    def on_pose(self, m, side):
        self.start.setdefault(side, m.pose.position)

    def on_diagnostics(self, array):
        for m in array.status:
            component = m.name.split(':')[0].lstrip('/')
            if not component.startswith('mesa_'):
                continue
            s = self.status.setdefault(component, {'ok': False, 'drops': 0, 'level': None, 'rejected': 0})
            if m.level == self.OK:
                s['ok'] = True
            if s['ok'] and m.level == self.ERROR and s['level'] != self.ERROR:
                s['drops'] += 1
            s['level'] = m.level
            s['rejected'] = sum(int(kv.value) for kv in m.values
                                if kv.key.startswith(('rejected', 'dropped')) and kv.value.isdigit())

    def up(self):
        return len(self.start) == 2 and all(
            self.status.get('mesa_%s/saras_arms_driver' % s, {}).get('ok') for s in SIDES)


def stream_targets(args, watch, stop):
    """Set-points around each arm's start position at ``args.target_rate`` until ``stop`` is set."""
    import rospy
    from geometry_msgs.msg import PoseStamped
    period = 1.0 / args.target_rate
    msgs = {}
    for side in SIDES:
        m = PoseStamped()
        m.header.frame_id = 'mesa_%s/sbs_world' % side
        msgs[side] = m
    t0 = time.monotonic()
    deadline = t0
    while not stop.is_set():
        t = time.monotonic() - t0
        for side in SIDES:
            m, p = msgs[side], watch.start[side]
            m.header.stamp = rospy.Time.now()
            m.pose.position.x = p.x + 0.005 * math.sin(2 * math.pi * 0.25 * t)
            m.pose.position.y = p.y + 0.005 * (1 - math.cos(2 * math.pi * 0.25 * t))
            m.pose.position.z = p.z
            watch.pubs[side].publish(m)
        deadline += period
        d = deadline - time.monotonic()
        if d > 0:
            time.sleep(d)
        elif d < -0.1:
            deadline = time.monotonic()


def record(args, watch):
    """Measures for ``args.duration`` s with the streams recorded by rosbag (a C++ subscriber, like
    the platform's recorder): a dict of the window's results."""
    import rospy
    bag = os.path.join(tempfile.mkdtemp(prefix='saras_arm_bench_bag_'), 'arm.bag')
    topics = ['/tf'] + ['/mesa_%s/%s' % (side, t) for side in SIDES
                        for t in ('ee_pose', 'joint_states', 'rcm_position')]
    recorder = subprocess.Popen(['rosbag', 'record', '--tcpnodelay', '-O', bag] + topics,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
    time.sleep(3.0)
    pids = arm_processes()
    r = {'rejected0': {k: v['rejected'] for k, v in watch.status.items()},
         'drops0': {k: v['drops'] for k, v in watch.status.items()}}
    pids['(this benchmark: subscribers + set-point publisher)'] = os.getpid()
    r['cpu0'] = {k: cpu_seconds(p) for k, p in pids.items()}
    r['load0'] = os.getloadavg()[0]
    t0 = time.monotonic()
    r['w0'] = rospy.Time.now()
    time.sleep(args.duration)
    r['w1'] = rospy.Time.now()
    r['dt'] = time.monotonic() - t0
    r['cpu'] = {k: cpu_seconds(p) for k, p in pids.items()}
    r['load1'] = os.getloadavg()[0]
    os.killpg(recorder.pid, signal.SIGINT)
    recorder.wait(30)
    r['stats'] = bag_stats(bag, r['w0'], r['w1'])
    return r


def print_report(args, watch, r):
    with open('/proc/loadavg') as f:
        loadavg = f.read().strip()
    dt, stats, cpu, cpu0 = r['dt'], r['stats'], r['cpu'], r['cpu0']
    print('SARAS arm ROS stack, both arms, %s, %.0f s, set-points at %.0f Hz, %d busy-loop processes, TF from %s; '
          'loadavg %.2f -> %.2f on %d CPUs (/proc/loadavg after: %s)'
          % ('inside the whole platform' if args.platform else 'alone', dt,
             args.control_rate if args.platform else args.target_rate, args.load,
             'saras_arms_state' if args.publish_tf else 'robot_state_publisher',
             r['load0'], r['load1'], os.cpu_count(), loadavg))
    print('| stream (recorded by rosbag) | messages | rate [Hz] | largest receive gap [ms] | largest stamp gap [ms] |')
    print('|---|---|---|---|---|')
    for k in sorted(stats):
        n, gap, sgap = stats[k]
        print('| %s | %d | %.1f | %.1f | %.1f |' % (k, n, n / (r['w1'] - r['w0']).to_sec(), 1e3 * gap, 1e3 * sgap))
    print('| process | CPU [% of one core] |')
    print('|---|---|')
    for k in sorted(cpu):
        if cpu[k] is not None and cpu0.get(k) is not None:
            print('| %s | %.1f |' % (k, 100.0 * (cpu[k] - cpu0[k]) / dt))
    print('| component | link drops | dropped/rejected inputs |')
    print('|---|---|---|')
    for k in sorted(watch.status):
        print('| %s | %d | %d |' % (k, watch.status[k]['drops'] - r['drops0'].get(k, 0),
                                      watch.status[k]['rejected'] - r['rejected0'].get(k, 0)))


def measure(args, procs):
    import rospy
    rospy.init_node('saras_arm_bench', disable_signals=True)
    watch = ArmWatch()
    end = time.monotonic() + 120.0
    while time.monotonic() < end and not watch.up():
        time.sleep(0.1)
    if len(watch.start) < 2:
        print('the arm stack did not come up (no ee_pose)')
        return 1
    time.sleep(2.0)
    stop = threading.Event()
    streamer = threading.Thread(target=stream_targets, args=(args, watch, stop), daemon=True)
    if not args.platform:           # on the platform the teleoperation commands the arms
        streamer.start()
    loaders = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(args.load)]
    try:
        r = record(args, watch)
    finally:
        for p in loaders:
            p.terminate()
            p.wait()
        stop.set()
        if streamer.is_alive():
            streamer.join(1.0)
    print_report(args, watch, r)
    rospy.signal_shutdown('done')
    return 0


if __name__ == '__main__':
    sys.exit(main())
