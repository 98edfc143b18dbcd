#!/usr/bin/env python3
"""Benchmark: the dVRK simulator node (dvrk_sim) as the platform runs it, alone or on a loaded host
(not a test).

Starts a private roscore, the dVRK arms' URDFs (saras_description/description.launch without
state publishers) and ``saras_simulation/dvrk.launch link_tf:=true`` (scripted console, 100 Hz,
the arms' joint TF from dvrk_sim), records the dVRK streams the platform's recorder records plus
/tf with rosbag (a C++ subscriber, like the recorder) for ``--duration`` seconds and prints:

  * each stream's rate (messages / window) and largest receive gap;
  * the CPU % (of one core, from /proc) of the dvrk_sim process and its CPU time per published
    sample (less dependent on what else runs);
  * dvrk_sim's own count of skipped samples (its ``skipped`` on /diagnostics).

optionally with ``--load N`` busy-loop processes (nice 0) competing for the CPUs, and ``--crtk``
to also serve the dVRK 2.x CRTK interface. Usage:
  dvrk_sim_ros.py [--duration S] [--load N] [--crtk]
Needs the workspace built (scripts/env.sh); prints one markdown table.
"""
import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time

from saras_simulation.bench_util import cpu_seconds, free_port, process_cmdlines, stop_process_groups

STREAMS = ['/dvrk/%s/%s' % (arm, t) for arm in ('PSM1', 'PSM2', 'ECM', 'MTML', 'MTMR')
           for t in ('position_cartesian_current', 'state_joint_current')] + \
    ['/dvrk/PSM1/state_jaw_current', '/dvrk/PSM2/state_jaw_current',
     '/dvrk/MTML/state_gripper_current', '/dvrk/MTMR/state_gripper_current']

LAUNCH = """<launch>
  <include file="$(find saras_description)/launch/description.launch">
    <arg name="state_publishers" value="false"/>
  </include>
  <include file="$(find saras_simulation)/launch/dvrk.launch">
    <arg name="link_tf" value="true"/>
    <arg name="crtk" value="{crtk}"/>
  </include>
</launch>
"""


def dvrk_sim_pid():
    """pid of the roslaunch'ed dvrk_sim (from its __name:= argument), or None."""
    return next((pid for pid, args in process_cmdlines() if b'__name:=dvrk_sim' in args), None)


class Skipped(object):
    """dvrk_sim's ``skipped`` counter, from /diagnostics."""

    def __init__(self):
        import rospy
        from diagnostic_msgs.msg import DiagnosticArray
        self.value = None
        self.sub = rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=20)

    def on_diagnostics(self, array):
        for s in array.status:
            if s.hardware_id == 'dvrk':
                for kv in s.values:
                    if kv.key == 'skipped':
                        self.value = int(kv.value)


def bag_stats(path, w0, w1):
    """{stream: [messages, largest receive gap [s]]} in [w0, w1]; /tf counted per message."""
    import rosbag
    out, last = {}, {}
    with rosbag.Bag(path) as b:
        for topic, _msg, t in b.read_messages(start_time=w0, end_time=w1, raw=True):
            s = out.setdefault(topic, [0, 0.0])
            if topic in last:
                s[1] = max(s[1], (t - last[topic]).to_sec())
            last[topic] = t
            s[0] += 1
    return out


def measure(args):
    import rospy
    rospy.init_node('dvrk_sim_bench', disable_signals=True)
    skipped = Skipped()
    end = time.monotonic() + 120.0
    pid = None
    while time.monotonic() < end and (pid is None or skipped.value is None):
        pid = pid or dvrk_sim_pid()
        time.sleep(0.2)
    if pid is None or skipped.value is None:
        print('dvrk_sim did not come up (no /diagnostics from it)')
        return 1
    bag = os.path.join(tempfile.mkdtemp(prefix='dvrk_sim_bench_'), 'dvrk.bag')
    recorder = subprocess.Popen(['rosbag', 'record', '--tcpnodelay', '-O', bag, '/tf'] + STREAMS,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
    loaders = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(args.load)]
    try:
        time.sleep(4.0)
        skipped0, cpu0, t0, w0 = skipped.value, cpu_seconds(pid), time.monotonic(), rospy.Time.now()
        time.sleep(args.duration)
        skipped1, cpu1, dt, w1 = skipped.value, cpu_seconds(pid), time.monotonic() - t0, rospy.Time.now()
    finally:
        for p in loaders:
            p.terminate()
            p.wait()
        os.killpg(recorder.pid, signal.SIGINT)
        recorder.wait(30)
    end = time.monotonic() + 30.0          # the C++ recorder closes the bag after its wrapper exits
    while not os.path.exists(bag) and time.monotonic() < end:
        time.sleep(0.2)
    stats = bag_stats(bag, w0, w1)
    window = (w1 - w0).to_sec()
    samples = stats.get(STREAMS[0], (0, 0.0))[0]
    print('dvrk_sim (link_tf, crtk %s), %.0f s, %d busy-loop processes on %d CPUs, loadavg %.1f; dvrk_sim '
          'CPU %.1f %% of one core, %.0f us per sample, %d samples skipped'
          % (args.crtk, dt, args.load, os.cpu_count(), os.getloadavg()[0], 100.0 * (cpu1 - cpu0) / dt,
             1e6 * (cpu1 - cpu0) / max(samples, 1), skipped1 - skipped0))
    print('| stream (recorded by rosbag) | messages | rate [Hz] | largest receive gap [ms] |')
    print('|---|---|---|---|')
    for k in ['/tf'] + STREAMS:
        n, gap = stats.get(k, (0, 0.0))
        print('| %s | %d | %.1f | %.1f |' % (k, n, n / window, 1e3 * gap))
    rospy.signal_shutdown('done')
    return 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--duration', type=float, default=20.0)
    ap.add_argument('--load', type=int, default=0, help='busy-loop processes (nice 0)')
    ap.add_argument('--crtk', action='store_true', help='also serve the CRTK interface')
    args, _ = ap.parse_known_args()
    os.environ['ROS_MASTER_URI'] = 'http://127.0.0.1:%d' % free_port()
    os.environ['ROS_HOSTNAME'] = '127.0.0.1'
    procs = []
    tmp = tempfile.mkdtemp(prefix='dvrk_sim_bench_')
    try:
        procs.append(subprocess.Popen(['roscore', '-p', os.environ['ROS_MASTER_URI'].rsplit(':', 1)[1]],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
        time.sleep(3.0)
        path = os.path.join(tmp, 'dvrk.launch')
        with open(path, 'w') as f:
            f.write(LAUNCH.format(crtk='true' if args.crtk else 'false'))
        procs.append(subprocess.Popen(['roslaunch', '--wait', path], stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, start_new_session=True))
        return measure(args)
    finally:
        stop_process_groups(procs, timeout=15.0)


if __name__ == '__main__':
    sys.exit(main())
