#!/usr/bin/env python3
"""State-stream rate of a SARAS arm link through a delayed TCP relay, per flow-control window.

  python3 scripts/cluster/window_rate.py [--delay-ms 200] [--rate 250] [--seconds 6] [WINDOW ...]

The arm simulator's Socket.IO server (saras_simulation.saras_arm_server) streams states at
``--rate``; a monitor client (saras_drivers.saras_arm_client) subscribes with ``state_window`` W
through a netem_relay TCP link with ``--delay-ms`` one way (both directions), all on 127.0.0.1,
no ROS. The server keeps at most W states in flight and the client acknowledges every W/3, so the
stream runs at between (W - W/3) / round trip and W / round trip at most: the window must cover
the bandwidth-delay product, rate x round trip, plus one acknowledgement batch. Prints one line per window: received
rate [Hz] after the first second, and the server's skipped-sample count.
"""
import argparse
import time

from saras_bringup.netem.config import parse_links
from saras_bringup.netem.relay import RelayThread
from saras_drivers import saras_arm_kinematics as sak
from saras_drivers.saras_arm_client import SarasArmClient
from saras_simulation.bench_util import free_port
from saras_simulation.saras_arm_model import SarasArmModel
from saras_simulation.saras_arm_server import SarasArmServer

KEY = bytes(range(32))
PA = [0.0, 0.5, 0.0, 1.3, 0.0, 1.0, 0.0]


def measure(window, delay_ms, rate, seconds):
    model = SarasArmModel(sak.load('left', PA), max_velocity=2.0)
    port = free_port()
    server = SarasArmServer(model, port=port, rate=2.0 * rate, state_rate=rate, key=KEY)
    server.start_in_thread()
    links = parse_links({'links': [{'name': 'arm', 'protocol': 'tcp', 'listen': '127.0.0.1:0',
                                    'target': '127.0.0.1:%d' % port, 'delay_ms': delay_ms,
                                    'reverse': {'delay_ms': delay_ms}}]})
    got = []
    try:
        with RelayThread(links) as relay:
            host, rport = relay.addresses()['arm']
            client = SarasArmClient('http://%s:%d' % (host, rport), KEY, 'mesa_left', subscribe_state=True,
                                    hold_on_connect=False, role='monitor', state_window=window,
                                    on_state=lambda s: got.append(time.monotonic()))
            client.start()
            try:
                if not client.wait_connected(10.0):
                    raise RuntimeError('no connection through the relay')
                time.sleep(seconds)
            finally:
                client.stop()
    finally:
        server.stop()
    t0 = got[0] + 1.0 if got else 0.0
    late = [t for t in got if t >= t0]
    hz = (len(late) - 1) / (late[-1] - late[0]) if len(late) > 1 else 0.0
    return hz, server.state_skipped


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('windows', nargs='*', type=int, default=[30, 150])
    parser.add_argument('--delay-ms', type=float, default=200.0)
    parser.add_argument('--rate', type=float, default=250.0)
    parser.add_argument('--seconds', type=float, default=6.0)
    args = parser.parse_args()
    rtt = 2e-3 * args.delay_ms
    for w in args.windows:
        hz, skipped = measure(w, args.delay_ms, args.rate, args.seconds)
        lo, hi = ((w - max(1, w // 3)) / rtt, w / rtt) if (w and rtt) else (float('inf'), float('inf'))
        print('window %4d: %6.1f Hz of %.0f (window bound %.0f-%.0f Hz), %d samples skipped by the server'
              % (w, hz, args.rate, lo, hi, skipped))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
