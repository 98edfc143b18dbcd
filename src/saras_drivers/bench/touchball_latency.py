#!/usr/bin/env python3
"""Benchmark: Touchball link latency and CPU at 1 kHz (not a test).

Starts a private roscore, ``touchball_receiver`` and ``touchball_console_sim`` (1 kHz, real UDP on
127.0.0.1), subscribes to ``/touchball/left/state`` and measures, per packet:
  * send -> publish: ``header.stamp`` (taken by the receiver just before publishing) minus the
    console's ``sender_time`` (wall clock just before sendto) = UDP + validation + twist;
  * send -> subscriber: arrival in this process minus ``sender_time`` (adds ROS TCP transport);
  * CPU % of the receiver and the console simulator processes (from /proc, over the window).
Usage: touchball_latency.py [--duration S] [--rate HZ]
"""
import argparse
import os
import signal
import subprocess
import sys
import time

import rospy

from saras_msgs.msg import HapticDeviceState

MASTER_PORT = 11631


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def pct(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, int(q * len(v)))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--duration', type=float, default=10.0)
    ap.add_argument('--rate', type=float, default=1000.0)
    args = ap.parse_args()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % MASTER_PORT)
    os.environ.update(env)
    procs = []
    try:
        procs.append(subprocess.Popen(['roscore', '-p', str(MASTER_PORT)], env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
        time.sleep(3.0)
        rx = subprocess.Popen(['rosrun', 'saras_drivers', 'touchball_receiver', '_port:=15501',
                               '_command_port:=15502', '_joint_states_rate:=0.0'], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        procs.append(rx)
        rospy.init_node('touchball_latency_bench', disable_signals=True)
        samples = []

        def on_state(m):
            if not m.stale:
                samples.append((time.time(), m.header.stamp.to_sec(), m.sender_time))
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, on_state, queue_size=10000,
                         tcp_nodelay=True)
        time.sleep(2.0)
        sim = subprocess.Popen(['rosrun', 'saras_drivers', 'touchball_console_sim', '_target_port:=15501',
                                '_command_port:=15502', '_rate:=%f' % args.rate], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        procs.append(sim)
        time.sleep(3.0)                                   # warm-up
        rx_pid = int(subprocess.check_output(['pgrep', '-n', '-f', 'touchball_receiver _port:=15501']))
        sim_pid = int(subprocess.check_output(['pgrep', '-n', '-f', 'touchball_console_sim _target_port']))
        n0 = len(samples)
        c_rx, c_sim, t0 = cpu_seconds(rx_pid), cpu_seconds(sim_pid), time.monotonic()
        time.sleep(args.duration)
        c_rx, c_sim, dt = cpu_seconds(rx_pid) - c_rx, cpu_seconds(sim_pid) - c_sim, time.monotonic() - t0
        window = samples[n0:]
    finally:
        for p in reversed(procs):
            try:
                os.killpg(p.pid, signal.SIGINT)
            except ProcessLookupError:
                pass
        for p in reversed(procs):
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
    if len(window) < 10:
        print('too few samples (%d): is the workspace built?' % len(window))
        return 1
    pub = [1e3 * (s - t) for _, s, t in window]
    e2e = [1e3 * (r - t) for r, _, t in window]
    stamps = [s for _, s, _ in window]
    rate = (len(stamps) - 1) / (stamps[-1] - stamps[0])
    load = os.getloadavg()[0]
    print('Touchball link, %.0f Hz stream for %.0f s (%d packets, host load %.1f on %d CPUs)'
          % (args.rate, args.duration, len(window), load, os.cpu_count()))
    print('| metric | p50 | p99 | max |')
    print('|---|---|---|---|')
    for name, v in (('UDP send -> pose/state published [ms]', pub),
                    ('UDP send -> subscriber callback [ms]', e2e)):
        print('| %s | %.3f | %.3f | %.3f |' % (name, pct(v, 0.5), pct(v, 0.99), max(v)))
    print('| publish rate [Hz] | %.1f | | |' % rate)
    print('| touchball_receiver CPU [%% of one core] | %.1f | | |' % (100.0 * c_rx / dt))
    print('| touchball_console_sim CPU [%% of one core] | %.1f | | |' % (100.0 * c_sim / dt))
    return 0


if __name__ == '__main__':
    sys.exit(main())
