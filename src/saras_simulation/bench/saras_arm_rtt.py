#!/usr/bin/env python3
"""Benchmark: SARAS arm Socket.IO command round trip and simulator CPU (not a test; no ROS).

Runs the simulator server core (saras_arm_server, 600 Hz integration, 300 Hz state stream) in a
child process on 127.0.0.1 and a client (saras_arm_client, websocket transport) here:
  * ack round trip of ``set_target`` / ``set_max_velocity`` (emit -> server validates and
    applies -> acknowledgement back);
  * command -> state: fire-and-forget ``set_target`` until a ``state`` event reports its id;
  * CPU % of the server process idle (streaming state) and under a 1 kHz set_target stream.
Usage: saras_arm_rtt.py [--n N]
"""
import argparse
import multiprocessing
import os
import socket
import sys
import threading
import time

import numpy as np

from saras_drivers import saras_arm_kinematics as sak
from saras_drivers import saras_arm_protocol as proto
from saras_drivers.saras_arm_client import SarasArmClient
from saras_simulation.saras_arm_model import SarasArmModel
from saras_simulation.bench_util import cpu_seconds
from saras_simulation.saras_arm_server import SarasArmServer

KEY = bytes(range(32))   # the arm link key of these tests
ARM = 'mesa_left'

PA = [0.0, 0.5, 0.0, 1.3, 0.0, 1.0, 0.0]


def serve(port, ready):
    model = SarasArmModel(sak.load('left', PA), max_velocity=3.0)
    server = SarasArmServer(model, '127.0.0.1', port, 600.0, 300.0, key=KEY,
                            event_rate=1e6, event_burst=10000)  # round trips back to back: no flood limit
    ready.set()
    server.run()



def pct(v, q):
    v = sorted(v)
    return v[min(len(v) - 1, int(q * len(v)))]


def round_trips(client, n, random_target, seen, cond):
    """Rows (name, [ms]) of the command round trips and of the command -> state latency."""
    rows = []
    rtt = []
    for _ in range(n):
        t = time.perf_counter()
        r = client.call(proto.EV_SET_TARGET, proto.make_set_target(client.next_id(), random_target()))
        rtt.append(1e3 * (time.perf_counter() - t))
        assert r['ok'], r
    rows.append(('set_target ack round trip [ms]', rtt))
    rtt = []
    for _ in range(n):
        t = time.perf_counter()
        client.call(proto.EV_SET_MAX_VELOCITY, proto.make_set_max_velocity(client.next_id(), 2.0))
        rtt.append(1e3 * (time.perf_counter() - t))
    rows.append(('set_max_velocity ack round trip [ms]', rtt))
    lat = []
    for _ in range(min(n, 300)):
        cid = client.next_id()
        t = time.perf_counter()
        client.emit(proto.EV_SET_TARGET, proto.make_set_target(cid, random_target()))
        with cond:
            cond.wait_for(lambda: cid in seen, 2.0)
        if cid in seen:
            lat.append(1e3 * (seen[cid] - t))
    rows.append(('set_target -> first state with it [ms]', lat))
    return rows


def server_cpu(client, pid, states, random_target):
    """CPU [% of one core] of the server streaming state, its state rate [Hz], then its CPU under a
    1 kHz target stream and that stream's rate [Hz]."""
    c0, t0, n0 = cpu_seconds(pid), time.monotonic(), len(states)
    time.sleep(3.0)
    idle_cpu = 100.0 * (cpu_seconds(pid) - c0) / (time.monotonic() - t0)
    state_rate = (len(states) - n0) / (time.monotonic() - t0)
    targets = [random_target() for _ in range(50)]
    c0, t0 = cpu_seconds(pid), time.monotonic()
    k = 0
    deadline = time.monotonic()
    while time.monotonic() - t0 < 3.0:
        client.send_target(targets[k % 50])
        k += 1
        deadline += 0.001
        d = deadline - time.monotonic()
        if d > 0:
            time.sleep(d)
    busy_dt = time.monotonic() - t0
    return idle_cpu, state_rate, 100.0 * (cpu_seconds(pid) - c0) / busy_dt, k / busy_dt


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--n', type=int, default=1000)
    args = ap.parse_args()
    s = socket.socket()
    s.bind(('127.0.0.1', 0))
    port = s.getsockname()[1]
    s.close()
    ready = multiprocessing.Event()
    child = multiprocessing.Process(target=serve, args=(port, ready), daemon=True)
    child.start()
    ready.wait(10)
    states = []
    seen = {}
    cond = threading.Condition()

    def on_state(st):
        with cond:
            states.append(st)
            seen[st['target_id']] = time.perf_counter()
            cond.notify_all()

    client = SarasArmClient('http://127.0.0.1:%d' % port, KEY, ARM, on_state=on_state, subscribe_state=True,
                            hold_on_connect=False)
    client.start()
    try:
        if not client.wait_connected(10.0):
            print('could not connect to the simulator server')
            return 1
        time.sleep(1.0)
        info = client.info
        model = SarasArmModel(sak.load('left', PA))        # same kinematics: build valid targets
        rng = np.random.RandomState(0)

        def random_target():
            q = model.q.copy()
            q[:3] = model.lower[:3] + rng.uniform(0.3, 0.7, 3) * (model.upper[:3] - model.lower[:3])
            return model.tip_in_base(q)[:3, 3]

        rows = round_trips(client, args.n, random_target, seen, cond)
        idle_cpu, state_rate, busy_cpu, busy_rate = server_cpu(client, child.pid, states, random_target)
    finally:
        client.stop()
        child.terminate()
        child.join(5)
    print('SARAS arm Socket.IO link (python-socketio %s transport, server %s, host load %.1f on %d CPUs)'
          % ('websocket', 'aiohttp', os.getloadavg()[0], os.cpu_count()))
    print('| metric | p50 | p99 | max |')
    print('|---|---|---|---|')
    for name, v in rows:
        print('| %s | %.3f | %.3f | %.3f |' % (name, pct(v, 0.5), pct(v, 0.99), max(v)))
    print('| state stream rate [Hz] (nominal %.0f) | %.1f | | |' % (info['state_rate'], state_rate))
    print('| simulator CPU, streaming state [%% of one core] | %.1f | | |' % idle_cpu)
    print('| simulator CPU, + %.0f Hz set_target [%% of one core] | %.1f | | |' % (busy_rate, busy_cpu))
    return 0


if __name__ == '__main__':
    sys.exit(main())
