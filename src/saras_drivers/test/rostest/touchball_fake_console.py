"""Helpers for the touchball rostests: a fake console that runs the v2 handshake and sends
authenticated protocol packets (the same touchball_protocol / touchball_session modules as
everything else) and records the command packets it gets back, and a recorder of the receiver's
/diagnostics status. The key comes from the test's ~key_file (the receiver's key)."""
import math
import socket
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray

from saras_drivers import keys
from saras_drivers import touchball_protocol as tp
from saras_drivers.touchball_session import ConsoleSession

#: name of the receiver's status on /diagnostics ("<node name>: <task>")
DIAGNOSTIC_NAME = 'touchball_receiver: console link'


class LinkDiagnostics(object):
    """Records the receiver's /diagnostics status: a list of (arrival wall time [s], status, values)
    with values = {key: value}; integers where the value is one."""

    def __init__(self, name=DIAGNOSTIC_NAME):
        self.name = name
        self.records = []
        self.lock = threading.Lock()
        self.sub = rospy.Subscriber('/diagnostics', DiagnosticArray, self._on, queue_size=100)

    def _on(self, msg):
        now = time.time()
        for st in msg.status:
            if st.name != self.name:
                continue
            values = {}
            for kv in st.values:
                values[kv.key] = int(kv.value) if kv.value.isdigit() else kv.value
            with self.lock:
                self.records.append((now, st, values))

    def wait_for(self, predicate, timeout=10.0, after=None):
        """The first record (arrival, status, values) arriving after wall time `after` (default: now)
        for which predicate(status, values) holds; None if none within timeout [s]."""
        after = time.time() if after is None else after
        end = time.monotonic() + timeout
        k = 0
        while time.monotonic() < end:
            with self.lock:
                new = self.records[k:]
                k = len(self.records)
            for r in new:
                if r[0] > after and predicate(r[1], r[2]):
                    return r
            time.sleep(0.05)
        return None

    def fresh(self, timeout=10.0):
        """The first complete report (with counters) that arrives from now on."""
        return self.wait_for(lambda st, v: 'packets received' in v, timeout)


def device(t, offset=0.0):
    """A known, smooth device state at time t [s] (used to check the published values)."""
    a = 0.5 * t + offset
    return tp.DeviceState((-0.12 + 0.01 * math.sin(a), 0.02 * math.cos(a), 0.07 + offset),
                          (0.0, 0.0, math.sin(a / 2), math.cos(a / 2)), 0.3 + 0.1 * math.sin(a),
                          int(t) % 2 == 0, False)


class FakeConsole(object):
    """:param key: deployment key (default: the test's ~key_file); ``connect()`` runs the handshake."""

    def __init__(self, port, command_port, source='127.0.0.1', key=None):
        self.mac = tp.Mac(key if key is not None else keys.read_key_file(rospy.get_param('~key_file')))
        self.session = ConsoleSession(self.mac)
        self.dest = ('127.0.0.1', port)
        self.tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.tx.bind((source, 0))
        self.rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.rx.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        # room for seconds of commands while this (Python, GIL-bound) reader is starved on a loaded host
        self.rx.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        self.rx.bind(('127.0.0.1', command_port))
        self.rx.settimeout(0.05)
        self.seq = 0
        self.epoch = time.time()       # sender_time = wall clock, as the real controller sends
        self.sent = {}
        self.send_wall = []            # wall time just before each sendto [s]
        self.commands = []             # (monotonic time, command datagram) with a valid tag and session
        self.received = []             # every datagram from the receiver
        self.lock = threading.Lock()
        self._stop = threading.Event()
        self._rx_thread = threading.Thread(target=self._receive, daemon=True)
        self._rx_thread.start()

    def _receive(self):
        while not self._stop.is_set():
            try:
                data, _ = self.rx.recvfrom(2048)
            except socket.timeout:
                continue
            except OSError:
                return
            now = time.monotonic()
            self.received.append((now, data))
            with self.lock:
                kind = self.session.handle(data, now)
            if kind == 'command':
                self.commands.append((now, data))

    @property
    def session_nonce(self):
        return self.session.session

    def connect(self, timeout=10.0):
        """Send hellos until a challenge binds the session; True when bound."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self.lock:
                if self.session.bound:
                    return True
                hello = tp.pack_hello(self.mac, self.session.console_nonce, self.seq, time.time())
            self.tx.sendto(hello, self.dest)
            time.sleep(0.1)
        return self.session.bound

    def send_raw(self, data):
        self.tx.sendto(data, self.dest)

    def send(self, t):
        devs = (device(t), device(t, 0.01))
        data = tp.pack_state(self.mac, self.session.session or 0, self.seq, self.epoch + t, devs)
        self.sent[self.seq] = devs
        self.seq += 1
        self.send_wall.append(time.time())
        self.tx.sendto(data, self.dest)
        return data

    def stream(self, rate, duration, t0=0.0):
        """Send at `rate` Hz for `duration` s (absolute schedule); returns the time of the last send."""
        period = 1.0 / rate
        start = time.monotonic()
        n = int(round(duration * rate))
        last = start
        for k in range(n):
            deadline = start + k * period
            d = deadline - time.monotonic()
            if d > 0:
                time.sleep(d)
            self.send(t0 + k * period)
            last = time.monotonic()
        return last

    def close(self):
        self._stop.set()
        self._rx_thread.join(1.0)
        self.tx.close()
        self.rx.close()
