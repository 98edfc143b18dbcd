#!/usr/bin/env python3
"""Benchmark: CPU time per packet of the Touchball cores, without ROS or sockets (not a test).

process_time() (this process's CPU, robust to a loaded host: waiting for a core is not counted)
per packet, best of --repeat runs of --n packets:
  * decode only: touchball_protocol.decode_state;
  * console simulator tick: command decode + scripted motion + 2 mass-damper models +
    calibration + pack_state (what touchball_console_sim does per 1 kHz period besides I/O).
Usage: touchball_cpu.py [--n N] [--repeat R]   (other arguments of bench/run are ignored)
"""
import argparse
import os
import sys

from saras_drivers import touchball_protocol as tp
from saras_simulation.bench_util import best_us
from saras_simulation.touchball_console import (ConsoleCalibration, HandDeviceModel, ScriptedMotion,
                                             TouchballConsole)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--n', type=int, default=3000)
    ap.add_argument('--repeat', type=int, default=5)
    args, _ = ap.parse_known_args()
    n = args.n
    mac = tp.Mac(bytes(range(32)))
    console = TouchballConsole([ScriptedMotion(), ScriptedMotion(phase=2.5)], mac,
                               [HandDeviceModel(), HandDeviceModel()],
                               [ConsoleCalibration(), ConsoleCalibration()], 0.1)
    session = 0x0123456789ABCDEF
    console.session.session = session              # bound (the handshake is not measured)
    console.session._alive = float('inf')
    packets = [console.packet(console.step(0.001, k * 1e-3), 1000.0 + k * 1e-3) for k in range(n)]
    cmd = tp.pack_command(mac, session, 1, 0.0, (tp.ZERO_COMMAND, tp.ZERO_COMMAND))

    def decode():
        for data in packets:
            tp.decode_state(data, mac, session)

    def tick():
        for k in range(n):
            console.handle_command(cmd, k * 1e-3)
            console.packet(console.step(0.001, k * 1e-3), 0.0)

    rows = [('decode_state (with HMAC check) only', best_us(decode, n, args.repeat)),
            ('console simulator tick (no I/O)', best_us(tick, n, args.repeat))]
    print('Touchball cores, CPU per packet (process_time, best of %d x %d); /proc/loadavg %s (%d CPUs)'
          % (args.repeat, n, ' '.join(open('/proc/loadavg').read().split()[:3]), os.cpu_count()))
    print('| path | CPU per packet [us] | share of one core at 1 kHz [%] |')
    print('|---|---|---|')
    for name, us in rows:
        print('| %s | %.1f | %.1f |' % (name, us, us / 10.0))
    return 0


if __name__ == '__main__':
    sys.exit(main())
