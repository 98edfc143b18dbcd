#!/usr/bin/env python3
"""Benchmark: Touchball link latency and CPU (not a test).

Starts a private roscore, ``touchball_receiver`` and ``touchball_console_sim`` (real UDP on
127.0.0.1), subscribes to the receiver's topics and measures, per packet of the left device:
  * UDP send -> pose callback: arrival of ``touchball/left/pose`` in this process minus the
    console's ``sender_time`` (wall clock just before sendto), paired through the header stamp
    the pose shares with ``touchball/left/state`` (which carries ``sender_time``). Includes UDP,
    validation, twist, the ROS TCP transport and this Python subscriber's wake-up;
  * UDP send -> receive stamp: ``header.stamp`` (the receiver's receive time) minus sender_time;
  * publish rate from the header stamps; CPU % of the receiver and the console simulator
    processes (utime + stime from /proc over the window, % of one core).
With ``--subscribers control`` (default) every control topic (8 x touchball/<side>/*, /tf) has a
subscriber, so the receiver pays its full per-packet publishing cost, as on the platform; with
``--subscribers pose`` only left/state and left/pose are subscribed.
Usage: touchball_latency.py [--duration S] [--rate HZ] [--subscribers control|pose]
                            [--realtime-priority N] [--receiver CMD] [--console CMD]
(--receiver / --console: another executable to compare, e.g. a previous version.)
"""
import argparse
import os
import subprocess
import sys
import threading
import time

import rospy
from geometry_msgs.msg import PoseStamped

from saras_msgs.msg import ComponentStatus, HapticDeviceState
from saras_simulation.bench_util import cpu_seconds, stop_process_groups

MASTER_PORT = 11631
CONTROL = ['/touchball/%s/%s' % (s, t) for s in ('left', 'right')
           for t in ('twist', 'buttons')] + ['/touchball/right/state', '/touchball/right/pose', '/tf']



def pct(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, int(q * len(v)))]


def wait_for(cond, timeout, what):
    """Poll cond() until true (start-up is slow on a loaded host); raise after timeout [s]."""
    end = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > end:
            raise RuntimeError('no %s after %.0f s' % (what, timeout))
        time.sleep(0.1)


def parse_args():
    ap = argparse.ArgumentParser()
    ap.add_argument('--duration', type=float, default=10.0)
    ap.add_argument('--rate', type=float, default=1000.0)
    ap.add_argument('--subscribers', choices=('control', 'pose'), default='control')
    ap.add_argument('--realtime-priority', type=int, default=10)
    ap.add_argument('--receiver', default='rosrun nodelet nodelet standalone saras_drivers/TouchballReceiver '
                    '__name:=touchball_receiver')
    ap.add_argument('--console', default='rosrun saras_simulation touchball_console_sim')
    return ap.parse_args()


class Recorder(object):
    """Subscribes to the receiver's topics: sender times of left/state by receive stamp, arrivals of
    left/pose, the touchball/status packet counter."""

    def __init__(self, subscribers):
        self.lock = threading.Lock()
        self.sender = {}              # receive stamp -> sender_time (left/state)
        self.status = []              # (wall time, packets accepted so far) from touchball/status
        self.poses = []               # (arrival wall time, receive stamp) (left/pose)
        rospy.Subscriber('/touchball/left/state', HapticDeviceState, self.on_state, queue_size=10000,
                         tcp_nodelay=True)
        rospy.Subscriber('/touchball/status', ComponentStatus,
                         lambda m: self.status.append((m.header.stamp.to_sec(), m.received)), queue_size=100)
        rospy.Subscriber('/touchball/left/pose', PoseStamped, self.on_pose, queue_size=10000,
                         tcp_nodelay=True)
        if subscribers == 'control':
            for t in CONTROL:
                rospy.Subscriber(t, rospy.AnyMsg, lambda _m: None, queue_size=10000, tcp_nodelay=True)

    def on_state(self, m):
        if not m.stale:
            with self.lock:
                self.sender[(m.header.stamp.secs, m.header.stamp.nsecs)] = m.sender_time

    def on_pose(self, m):
        t = time.time()
        with self.lock:
            self.poses.append((t, (m.header.stamp.secs, m.header.stamp.nsecs)))

    def count(self):
        with self.lock:
            return len(self.poses)

    def window(self, n0, n1):
        """(arrival, receive stamp [s], sender time) of the poses n0..n1 whose state arrived."""
        with self.lock:
            w = [(a, s, self.sender.get(s)) for a, s in self.poses[n0:n1]]
        return [(a, s[0] + 1e-9 * s[1], t) for a, s, t in w if t is not None]


def stop(procs):
    stop_process_groups(procs, timeout=10.0)


def console_key():
    """The console link key of this run: $SARAS_KEY_DIR/console.key (bench/run creates it)."""
    return os.path.join(os.environ.get('SARAS_KEY_DIR', '/etc/saras'), 'console.key')


def measure(args, env, procs):
    """Starts the receiver and the console simulator (appended to ``procs``) and measures for
    ``args.duration`` s: (recorder, window, CPU seconds of receiver and simulator, dt, w0, w1)."""
    rx = subprocess.Popen(args.receiver.split() + [
        '_port:=15501', '_command_port:=15502', '_joint_states_rate:=0.0', '_key_file:=' + console_key(),
        '_realtime_priority:=%d' % args.realtime_priority], env=env,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    procs.append(rx)
    rospy.init_node('touchball_latency_bench', disable_signals=True)
    rec = Recorder(args.subscribers)
    wait_for(lambda: rec.status, 30.0, 'touchball/status from the receiver')
    time.sleep(1.0)                                   # subscriber connections
    sim = subprocess.Popen(args.console.split() + [
        '_target_port:=15501', '_command_port:=15502', '_rate:=%f' % args.rate,
        '_key_file:=' + console_key()], env=env,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    procs.append(sim)
    wait_for(lambda: rec.poses, 30.0, 'touchball/left/pose (console simulator streaming)')
    time.sleep(2.0)                                   # warm-up
    n0 = rec.count()
    c_rx, c_sim, t0, w0 = cpu_seconds(rx.pid), cpu_seconds(sim.pid), time.monotonic(), time.time()
    time.sleep(args.duration)
    c_rx, c_sim, dt = cpu_seconds(rx.pid) - c_rx, cpu_seconds(sim.pid) - c_sim, time.monotonic() - t0
    w1 = time.time()
    n1 = rec.count()
    time.sleep(1.0)                                   # let the state of the last poses arrive
    return rec, rec.window(n0, n1), c_rx, c_sim, dt, w0, w1


def report(args, rec, window, c_rx, c_sim, dt, w0, w1, load0):
    # packets the receiver accepted during the CPU window (status counter, 10 Hz, interpolated
    # to the window ends by the nearest samples)
    inside = [(t, n) for t, n in rec.status if w0 - 0.1 <= t <= w1 + 0.1]
    accepted = (inside[-1][1] - inside[0][1]) * dt / (inside[-1][0] - inside[0][0]) if len(inside) > 2 else 0
    if len(window) < 10:
        print('too few samples (%d): is the workspace built?' % len(window))
        return 1
    e2e = [1e3 * (a - t) for a, _, t in window]
    rcv = [1e3 * (s - t) for _, s, t in window]
    stamps = [s for _, s, _ in window]
    rate = (len(stamps) - 1) / (stamps[-1] - stamps[0])
    load1 = open('/proc/loadavg').read().split()[:3]
    print('Touchball link, %.0f Hz stream for %.0f s (%d packets), subscribers: %s, receiver '
          'realtime_priority %d; /proc/loadavg before %s, after %s (%d CPUs)'
          % (args.rate, args.duration, len(window), args.subscribers, args.realtime_priority,
             ' '.join(load0), ' '.join(load1), os.cpu_count()))
    print('| metric | p50 | p99 | max |')
    print('|---|---|---|---|')
    for name, v in (('UDP send -> left/pose callback [ms]', e2e),
                    ('UDP send -> receive stamp [ms]', rcv)):
        print('| %s | %.3f | %.3f | %.3f |' % (name, pct(v, 0.5), pct(v, 0.99), max(v)))
    print('| publish rate [Hz] | %.1f | | |' % rate)
    print('| touchball_receiver CPU [%% of one core] | %.1f | | |' % (100.0 * c_rx / dt))
    print('| touchball_receiver CPU per accepted packet [us] | %.0f | | |'
          % (1e6 * c_rx / accepted if accepted else float('nan')))
    print('| packets accepted by the receiver [Hz] | %.1f | | |' % (accepted / dt))
    print('| touchball_console_sim CPU [%% of one core] | %.1f | | |' % (100.0 * c_sim / dt))
    return 0


def main():
    args = parse_args()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % MASTER_PORT)
    os.environ.update(env)
    procs = []
    load0 = open('/proc/loadavg').read().split()[:3]
    try:
        procs.append(subprocess.Popen(['roscore', '-p', str(MASTER_PORT)], env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
        time.sleep(3.0)
        results = measure(args, env, procs)
    finally:
        stop(procs)
    return report(args, *results, load0=load0)


if __name__ == '__main__':
    sys.exit(main())
