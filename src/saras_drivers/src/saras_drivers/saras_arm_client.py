"""Socket.IO client of one SARAS arm (ROS-agnostic core of ``saras_arms_driver`` and
``saras_arms_state``).

* Connects over the websocket transport; retries with exponential backoff (``backoff_initial`` ..
  ``backoff_max`` seconds, +-50 % jitter) both for the first connection and after a drop.
* Never queues commands: while disconnected a command is refused (returns False / raises), and
  after a reconnection nothing is replayed. On every (re)connection the client sends ``hold``
  (if ``hold_on_connect``) so the arm stays where it is until a fresh command arrives.
* Validates every ``state`` event with :mod:`saras_arm_protocol` before handing it on.
* Authenticates every connection (:mod:`saras_arm_auth`: a fresh connect ``auth`` payload, HMAC of
  the arm link's key, in ``role`` command or monitor); ``tls_ca_file`` (with an ``https://`` URL)
  verifies the server's certificate against that CA (wss).

Threads and load (why the stock python-socketio client is not used as is): python-engineio 4.3's
threaded client starts a new thread for every received message, so a 300 Hz ``state`` stream
costs 300 thread creations per second and its handlers run concurrently, in any order. Here the
websocket reader thread dispatches every Socket.IO packet itself, in order, and only *stores* a
``state`` payload in a bounded mailbox (``state_queue`` entries); a single dispatcher thread
validates the states in order and calls ``on_state``. A short burst is delivered completely; a
consumer slower than the stream for longer loses the oldest states (counted in ``conflated``)
instead of queueing them without bound, and the reader keeps draining the socket, so Engine.IO
pings are answered on time however slow the consumer is (a backlog of states in front of a ping
would drop the link on a loaded host). A *reader* slower than the stream (a process starved of
CPU) is bounded by flow control: the client subscribes with ``state_window`` and reports the states
it received (``state_ack`` every window/3), and the server keeps at most ``state_window`` states in
flight, skipping samples beyond it. Without it, the kernel's autotuned socket buffers hold seconds
of states in front of such a reader.
"""

import collections
import json
import logging
import queue
import random
import threading
import time

import engineio
import socketio
from engineio import packet as eio_packet

import requests

from saras_drivers import saras_arm_auth as auth
from saras_drivers import saras_arm_protocol as proto


class _InlineEngineIOClient(engineio.Client):
    """Engine.IO client that dispatches messages in its reader thread (in order, no thread per
    message; handlers must not block: they only count, store or hand over) and, on the websocket
    transport, writes every packet in the sender's own thread (websocket-client serialises
    concurrent writers with its lock), in the order of the calls, instead of handing each one to a
    writer thread through a queue (a thread wake-up per set-point). A failed write is logged; the
    reader sees the broken connection and the client reconnects, as with the writer thread."""

    def __init__(self, *args, **kwargs):
        super(_InlineEngineIOClient, self).__init__(*args, **kwargs)
        self._inline = False            # this connection's writer task took over the queue
        self._inline_lock = threading.Lock()

    def _receive_packet(self, pkt):
        if pkt.packet_type == eio_packet.MESSAGE:
            self._trigger_event('message', pkt.data, run_async=False)
        else:
            super(_InlineEngineIOClient, self)._receive_packet(pkt)

    def _send_packet(self, pkt):
        with self._inline_lock:
            if not (self._inline and self.state == 'connected'):
                # handshake (before the writer task runs) or another transport: queued
                return super(_InlineEngineIOClient, self)._send_packet(pkt)
        self._write(pkt)

    def _write(self, pkt):
        try:
            if pkt.binary:
                self.ws.send_binary(pkt.encode())
            else:
                self.ws.send(pkt.encode())
        except Exception as e:  # pylint: disable=broad-except
            self.logger.warning('WebSocket write failed (%s): the connection is going down', e)

    def _write_loop(self):
        """Websocket: writes what was queued during the handshake, then switches the connection
        to writes in the senders' threads and only waits for its end (None)."""
        if self.current_transport != 'websocket':
            return super(_InlineEngineIOClient, self)._write_loop()
        with self._inline_lock:         # nothing is queued or written inline meanwhile: in order
            if not self._write_queued(block=False):
                return
            self._inline = True
        try:
            while self.state == 'connected':
                if not self._write_queued(block=True):
                    return
        finally:
            with self._inline_lock:
                self._inline = False

    def _write_queued(self, block):
        """Writes the queued packets (waiting up to 1 s for one when ``block``) until the queue is
        empty; False once the end of the connection (None) was taken."""
        while True:
            try:
                pkt = self.queue.get(timeout=1.0) if block else self.queue.get(block=False)
            except queue.Empty:
                return True
            self.queue.task_done()
            if pkt is None:
                return False
            self._write(pkt)
            if block:
                return True


def skip_utf8_validation(ws):
    """Turn off websocket-client's pure-Python UTF-8 check of every received text frame (a loop
    over each byte: ~15 % of the state node's active CPU at 300 states/s). Nothing is lost: the
    text is decoded with ``bytes.decode('utf-8')`` afterwards, so a malformed frame still raises in
    the reader, which drops the connection as the check would. Best effort (private attributes of
    websocket-client 1.x; anything else is left alone). Returns True when applied."""
    applied = False
    for part in ('frame_buffer', 'cont_frame'):
        obj = getattr(ws, part, None)
        if obj is not None and hasattr(obj, 'skip_utf8_validation'):
            obj.skip_utf8_validation = True
            applied = True
    return applied


class _SocketIOClient(socketio.Client):
    def _engineio_client_class(self):
        return _InlineEngineIOClient


class NotConnected(RuntimeError):
    pass


def _emit_json(sio, event, payload):
    """``sio.emit(event, payload)`` on the default namespace for a payload of plain JSON types (the
    protocol's: never binary), the same Socket.IO EVENT text without python-socketio's packet object
    and its recursive search for binary attachments (most of an emit's cost)."""
    if '/' not in sio.namespaces:
        raise socketio.exceptions.BadNamespaceError('/ is not a connected namespace.')
    sio.eio.send('2' + json.dumps([event, payload], separators=(',', ':')))


class SarasArmClient(object):
    """:param url: e.g. ``http://127.0.0.1:5001``; callbacks are called from the client's
    threads: ``on_state(dict)`` from the dispatcher thread (in order; the oldest are dropped when more
    than ``state_queue`` wait),
    ``on_error(dict)`` and ``on_connection(bool)`` from the reader/supervisor threads (they must
    not block)."""

    def __init__(self, url, key, arm, on_state=None, on_error=None, on_connection=None,
                 subscribe_state=False, hold_on_connect=True, backoff_initial=0.2,
                 backoff_max=5.0, logger=None, state_queue=30, state_window=30, role='command',
                 tls_ca_file=''):
        if not 0.0 < backoff_initial <= backoff_max:
            raise ValueError('need 0 < backoff_initial <= backoff_max')
        if not int(state_queue) >= 1:
            raise ValueError('state_queue must be >= 1')
        if not int(state_window) >= 0:
            raise ValueError('state_window must be >= 0 (0 = no flow control)')
        if role not in auth.ROLES:
            raise ValueError('role must be one of %s' % (auth.ROLES,))
        self.key, self.arm, self.role = bytes(key), arm, role
        self.state_window = int(state_window)
        self._ack_every = max(1, self.state_window // 3)
        self._conn_received = 0        # states received on the current connection (state_ack)
        self.url = url
        self.on_state = on_state
        self.on_error = on_error
        self.on_connection = on_connection
        self.subscribe = subscribe_state
        self.hold_on_connect = hold_on_connect
        self.backoff_initial = float(backoff_initial)
        self.backoff_max = float(backoff_max)
        self.log = logger or logging.getLogger('saras_arm_client')
        # built-in reconnection is disabled: one supervisor thread owns (re)connection.
        session = None
        if tls_ca_file:
            session = requests.Session()
            session.verify = tls_ca_file         # engine.io uses it for the wss handshake too
        self.sio = _SocketIOClient(reconnection=False, logger=False, engineio_logger=False,
                                   handle_sigint=False, http_session=session)
        self.connected = False
        self.connections = 0
        self.states = 0                # states handed to on_state
        self.received_states = 0       # state events received
        self.conflated = 0             # states dropped (mailbox full) before on_state took them
        self.bad_states = 0
        self._mailbox = collections.deque(maxlen=int(state_queue))   # unprocessed state payloads
        self._mail = threading.Condition(threading.Lock())
        self._dispatcher = None
        self.errors = 0
        self.info = None
        self._next_id = 0
        self._id_lock = threading.Lock()
        self._stop = threading.Event()
        self._lost = threading.Event()
        self._thread = None
        self._register()

    def next_id(self):
        with self._id_lock:
            self._next_id += 1
            return self._next_id

    def _register(self):
        sio = self.sio

        @sio.event
        def connect():
            # ``connected`` (commands allowed) is raised only after ``hold`` went out, in
            # _on_connected: a command can never be overtaken by the hold of its own connection.
            self.connections += 1

        @sio.event
        def disconnect():
            self.connected = False
            self._lost.set()
            if self.on_connection:
                self.on_connection(False)

        @sio.on(proto.EV_STATE)
        def state(payload):
            # reader thread: store and wake the dispatcher, nothing else
            with self._mail:
                self.received_states += 1
                if len(self._mailbox) == self._mailbox.maxlen:
                    self.conflated += 1          # the oldest one falls out
                self._mailbox.append(payload)
                self._mail.notify()
            self._conn_received += 1
            if self.state_window and self._conn_received % self._ack_every == 0:
                try:
                    _emit_json(self.sio, proto.EV_STATE_ACK, {'received': self._conn_received})
                except Exception:  # pylint: disable=broad-except
                    pass                         # link going down: the supervisor reconnects

        @sio.on(proto.EV_ERROR)
        def error(payload):
            self.errors += 1
            if self.on_error:
                self.on_error(payload if isinstance(payload, dict) else {'message': str(payload)})

    # ------------------------------------------------------------------ connection
    def start(self):
        self._thread = threading.Thread(target=self._supervise, name='saras_arm_client', daemon=True)
        self._thread.start()
        if self.subscribe:
            self._dispatcher = threading.Thread(target=self._dispatch, name='saras_arm_state',
                                                daemon=True)
            self._dispatcher.start()

    def stop(self):
        self._stop.set()
        self._lost.set()
        with self._mail:
            self._mail.notify_all()
        try:
            self.sio.disconnect()
        except Exception:
            pass
        if self._thread is not None:
            self._thread.join(3.0)
        if self._dispatcher is not None:
            self._dispatcher.join(3.0)

    def _dispatch(self):
        """Dispatcher thread: validate the queued states in order and hand them to ``on_state``."""
        while True:
            with self._mail:
                while not self._mailbox and not self._stop.is_set():
                    self._mail.wait()
                if self._stop.is_set():
                    return
                payload = self._mailbox.popleft()
            try:
                s = proto.parse_state(payload)
            except proto.ProtocolError as e:
                self.bad_states += 1
                self.log.error('malformed state event: %s', e)
                continue
            self.states += 1
            if self.on_state:
                try:
                    self.on_state(s)
                except Exception as e:  # pylint: disable=broad-except
                    self.log.error('state callback failed: %s', e)

    def wait_connected(self, timeout):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.connected:
                return True
            time.sleep(0.01)
        return self.connected

    def _on_connected(self):
        if self.hold_on_connect:
            self.sio.emit(proto.EV_HOLD, {'id': self.next_id()})
        if self.subscribe:
            self._conn_received = 0
            r = self.sio.call(proto.EV_SUBSCRIBE_STATE,
                              {'window': self.state_window} if self.state_window else {}, timeout=2.0)
            if isinstance(r, dict):
                self.info = r.get('info')
        self.connected = self.sio.connected
        if self.on_connection:
            self.on_connection(True)

    def _supervise(self):
        backoff = self.backoff_initial
        while not self._stop.is_set():
            try:
                self._lost.clear()
                self.sio.connect(self.url, transports=['websocket'], wait_timeout=2,
                                 auth=auth.make_auth(self.key, self.arm, self.role))
                skip_utf8_validation(getattr(self.sio.eio, 'ws', None))
                self._on_connected()
                backoff = self.backoff_initial
                self._lost.wait()
            except Exception as e:  # connection refused, timeout, server gone mid-handshake
                self.log.debug('connect to %s failed: %s', self.url, e)
            # Let python-socketio finish its own disconnect handling (its reader thread iterates
            # the namespaces) before touching the client; then make sure the transport is closed.
            end = time.monotonic() + 2.0
            while self.sio.eio.state == 'connected' and self.sio.connected and \
                    time.monotonic() < end and not self._stop.is_set():
                time.sleep(0.01)
            if self.sio.eio.state == 'connected':
                try:
                    self.sio.disconnect()
                except Exception:
                    pass
            self.connected = False
            if self._stop.is_set():
                break
            self._stop.wait(backoff * random.uniform(0.5, 1.5))
            backoff = min(2.0 * backoff, self.backoff_max)

    # ------------------------------------------------------------------ commands
    def emit(self, event, payload):
        """Fire-and-forget; returns False (nothing queued) when not connected."""
        if not self.connected:
            return False
        try:
            _emit_json(self.sio, event, payload)
            return True
        except Exception:
            return False

    def call(self, event, payload, timeout=1.0):
        """Send and wait for the ack dict; raises :class:`NotConnected` or TimeoutError."""
        if not self.connected:
            raise NotConnected('not connected to %s' % self.url)
        try:
            r = self.sio.call(event, payload, timeout=timeout)
        except socketio.exceptions.TimeoutError:
            raise TimeoutError('%s: no answer within %g s' % (event, timeout))
        except socketio.exceptions.BadNamespaceError:
            raise NotConnected('not connected to %s' % self.url)
        if not isinstance(r, dict):
            raise TimeoutError('%s: malformed answer %r' % (event, r))
        return r

    def hold(self):
        """``hold``: the arm stops where it is (fire-and-forget; False when not connected)."""
        return self.emit(proto.EV_HOLD, {'id': self.next_id()})

    def send_target(self, position, orientation=None):
        return self.emit(proto.EV_SET_TARGET,
                         proto.make_set_target(self.next_id(), position, orientation, time.time()))
