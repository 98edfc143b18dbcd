"""Socket.IO server of one simulated SARAS arm (ROS-agnostic core of ``saras_arm_sim``).

python-socketio ``AsyncServer`` on aiohttp, one asyncio loop per arm:

* a control task wakes at ``state_rate`` Hz, integrates :class:`SarasArmModel` to each sample
  instant of that grid in sub-steps of at most ``1/rate`` s (``rate`` >= 500 Hz, the model's
  internal integration rate) and emits one ``state`` event per sample to each subscribed client;
  after a late wake-up it emits the samples it missed (up to ``max_catch_up`` periods), so the
  stream keeps its rate and exact sample times on a loaded host, delivered in a short burst;
* every command first emits the samples owed and integrates the model up to the instant it is
  handled, then takes effect there, not at the next tick;
* the sample grid is re-anchored against the time taken *inside* the emission lock (a time taken
  before waiting for the lock can be old behind a queue of command tasks), so the sample times
  stay on real time however long the queue;
* event handlers validate payloads with :mod:`saras_arm_protocol` and answer with an ack; a rejected
  command also gets an ``error`` event and changes nothing. They run as asyncio tasks (FIFO, so in
  the order sent);
* set-points are judged when they are executed, after the wait for the emission lock (behind a
  queue of commands on a starved host that wait is long): the first ``set_target`` task to get
  there executes the newest set-point received so far, the tasks of the older ones it replaced
  skip (``superseded``: the newest wins, as a servo loop sampling its set-point), and a set-point
  older than ``max_target_age`` then is dropped (``stale``). Judged when its task started
  instead, a backlog of old set-points was executed one after the other: with the commanding
  driver killed, the arm kept moving for 360 ms;
* back-pressure: a client whose Engine.IO send queue still holds ``max_backlog`` packets (it reads
  slower than the stream for a while) skips that state sample (counted in ``state_skipped``), so neither the
  state latency nor the Engine.IO ping behind it grows without bound;
* flow control: a client that subscribed with a ``window`` gets at most that many states in flight
  (sent, not yet reported received by its ``state_ack``); further samples are skipped (counted in
  ``state_skipped``). The Engine.IO queue check alone does not bound the latency: the kernel's
  autotuned socket buffers (MBs on loopback) hold seconds of states in front of a reader that is
  slower than the stream (a starved client process), and the queue stays empty meanwhile;
* when the client that commanded motion disconnects, the arm holds (target := current joints);
* security (docs/security.md): a connection is refused before any event unless its ``auth``
  payload authenticates (:mod:`saras_drivers.saras_arm_auth`, key of the arm link); only the newest
  authenticated ``command`` session may command (an older one is held and dropped); every session's
  events are rate-limited and a flooding session is dropped; Engine.IO messages above
  ``MAX_MESSAGE_BYTES`` are refused; optional TLS (``ssl_context``).
"""

import asyncio
import logging
import os
import threading
import time

import socketio
from aiohttp import web

from saras_drivers import saras_arm_auth as auth
from saras_drivers import saras_arm_protocol as proto
from saras_simulation.saras_arm_model import matrix_to_quat


def _cmd_id(payload):
    """The command id of a payload (0 when missing or not an int)."""
    cmd_id = payload.get('id', 0) if isinstance(payload, dict) else 0
    return cmd_id if isinstance(cmd_id, int) and not isinstance(cmd_id, bool) else 0


class SarasArmServer(object):
    """:param model: :class:`SarasArmModel`; :param rate: integration rate [Hz];
    :param state_rate: state stream rate [Hz] (rate must be a multiple);
    :param key: the arm link's key (bytes); :param arm: this arm's name in the auth payload;
    :param event_rate, event_burst: per-session event rate limit [events/s], burst;
    :param ssl_context: serve wss/https with it (None: plain)."""

    def __init__(self, model, host='127.0.0.1', port=5000, rate=1000.0, state_rate=250.0,
                 logger=None, ping_interval=1.0, ping_timeout=5.0, max_backlog=32,
                 max_catch_up=30, max_target_age=0.0, key=None, arm='mesa_left', max_skew=30.0,
                 event_rate=1000.0, event_burst=200, ssl_context=None, realtime_priority=0):
        if key is None:
            raise ValueError('the arm link needs a key (saras_drivers.keys)')
        if not (isinstance(realtime_priority, int) and 0 <= realtime_priority <= 99):
            raise ValueError('realtime_priority must be an integer in [0, 99], got %r' % (realtime_priority,))
        self.realtime_priority = realtime_priority
        self.realtime = False        # the server thread runs SCHED_FIFO
        self.gate = auth.SessionGate(auth.Authenticator(key, arm, max_skew), event_rate, event_burst)
        self.ssl_context = ssl_context
        self._refusal_logged = {}    # reason -> time of the last log line
        if not rate >= 500.0:
            raise ValueError('rate must be >= 500 Hz, got %r' % rate)
        if not 0.0 < state_rate <= rate:
            raise ValueError('state_rate must be in (0, rate], got %r' % state_rate)
        if not max_backlog >= 1:
            raise ValueError('max_backlog must be >= 1, got %r' % max_backlog)
        self.model = model
        # integration sub-step: at most 1/rate [s] (the model may already use a finer one)
        model.max_step = min(model.max_step, 1.0 / float(rate))
        self.host, self.port = host, int(port)
        self.rate = float(rate)
        self.state_rate = float(state_rate)
        self.max_backlog = int(max_backlog)
        self.max_catch_up = int(max_catch_up)
        if not max_target_age >= 0.0:
            raise ValueError('max_target_age must be >= 0 s (0 = no limit), got %r' % max_target_age)
        self.max_target_age = float(max_target_age)
        self.stale_targets = 0       # set_target commands older than max_target_age when handled
        self.superseded_targets = 0  # set_target commands a newer waiting one replaced (not executed)
        self._target_arrivals = 0    # set_target commands admitted so far (newest wins)
        self._newest_target = (0, None)     # (arrival, payload) of the newest set_target
        self._executed_arrival = 0   # arrival of the newest set_target executed
        self.log = logger or logging.getLogger('saras_arm_server')
        # Engine.IO heartbeat: a client that does not answer a ping (sent every ping_interval [s])
        # within ping_timeout [s] is dropped; a client sees a dead server after the same sum.
        self.sio = socketio.AsyncServer(async_mode='aiohttp', logger=False, engineio_logger=False,
                                        ping_interval=ping_interval, ping_timeout=ping_timeout,
                                        max_http_buffer_size=proto.MAX_MESSAGE_BYTES)
        self.app = web.Application()
        self.sio.attach(self.app)
        self.commander = None
        self.accepted = 0
        self.rejected = 0
        self.state_seq = 0
        self.clients = 0
        self.sids = set()
        self.events = {}             # accepted commands per event name
        self.max_late = 0.0          # worst control-step lateness [s]
        self.state_skipped = 0       # state samples not sent to a backlogged client
        self.missed = 0              # grid samples lost to a wake-up later than max_catch_up periods
        self.subscribers = set()     # sids in the state stream
        self._flow = {}              # sid -> [window, states sent, states the client received]
        self._period = 1.0 / self.state_rate
        self._deadline = time.monotonic() + self._period   # next sample instant (monotonic)
        self._emit_lock = None       # asyncio.Lock, created in the server's loop
        self._fk_key = None          # joint vector of the cached forward kinematics
        self._fk = None
        self._wall_offset = time.time() - time.monotonic()
        self._last_step = time.monotonic()
        self._sample_time = self._last_step + self._wall_offset
        self.ready = threading.Event()
        self._stop = None
        self._loop = None
        self._thread = None
        self._register()

    # ------------------------------------------------------------------ handlers
    def _register(self):
        sio = self.sio
        sio.on('connect', self._on_connect)
        sio.on('disconnect', self._on_disconnect)
        for event, fn in (('set_target', self._set_target), ('set_max_velocity', self._set_max_velocity),
                          ('set_clip', self._set_clip), ('hold', self._hold)):
            sio.on(event, self._commanding(event, fn))
        sio.on(proto.EV_SUBSCRIBE_STATE, self._on_subscribe_state)
        sio.on(proto.EV_STATE_ACK, self._on_state_ack)

    async def _on_connect(self, sid, environ, auth_payload=None):
        try:
            old = self.gate.connect(sid, auth_payload)
        except auth.AuthError as e:
            self._refused(sid, e)
            raise socketio.exceptions.ConnectionRefusedError('unauthorized')
        self.clients += 1
        self.sids.add(sid)
        self.log.info('client %s connected (%s)', sid, self.gate.roles[sid])
        if old is not None:
            # a newer authenticated command session: the old one may not command any more
            now = await self._sample_until()
            self.advance(now)
            self.model.hold()
            self.log.warning('command session %s superseded by %s: holding, dropping it', old, sid)
            asyncio.ensure_future(self.sio.disconnect(old))

    async def _on_disconnect(self, sid):
        self.gate.disconnect(sid)
        if sid not in self.sids:
            return
        self.clients -= 1
        self.sids.discard(sid)
        self.subscribers.discard(sid)
        self._flow.pop(sid, None)
        if sid == self.commander:
            now = await self._sample_until()
            self.advance(now)
            self.model.hold()
            self.commander = None
            self.log.warning('commanding client %s disconnected: holding', sid)

    def _commanding(self, event, fn):
        """Handler of command ``event``: runs ``fn(payload)``; a client whose command succeeds
        becomes the commander."""
        async def handler(sid, payload=None):
            r = await self._run(sid, event, payload, fn)
            if r['ok']:
                self.commander = sid
            return r
        return handler

    async def _run(self, sid, event, payload, fn):
        cmd_id = _cmd_id(payload)
        refusal = self._admit(sid, True)
        if refusal is not None:     # rate limit, or not the commanding session: no motion, no work
            return proto.reply(False, refusal, 'refused', 0)
        # first the state samples a late loop still owes (so they are not overtaken by the
        # command), then the command acts now: no await between advance() and fn()
        if event in ('set_target', 'set_clip') and self._stale(payload):
            return self._drop_stale(event, cmd_id)
        if event == 'set_target':
            self._target_arrivals += 1
            self._newest_target = (self._target_arrivals, payload)
        now = await self._sample_until()
        # the wait for the emission lock can be long behind a queue of commands: the newest
        # set-point received is executed by the first of their tasks that gets here, the older
        # ones skip, and a set-point is judged when it is executed (module doc)
        if event == 'set_target':
            arrival, payload = self._newest_target
            if arrival <= self._executed_arrival:
                self.superseded_targets += 1
                return proto.reply(False, proto.SUPERSEDED, 'a newer set_target was executed', cmd_id)
            self._executed_arrival = arrival
            cmd_id = _cmd_id(payload)
        if event in ('set_target', 'set_clip') and self._stale(payload):
            return self._drop_stale(event, cmd_id)
        try:
            self.advance(now)           # (a no-op if the loop already sampled past now)
            extra = fn(payload)
        except proto.ProtocolError as e:
            self.rejected += 1
            await self.sio.emit(proto.EV_ERROR, {'id': cmd_id, 'event': event, 'code': e.code,
                                                 'message': e.message}, to=sid)
            return proto.reply(False, e.code, e.message, cmd_id)
        except Exception as e:  # never let a payload kill the server
            self.rejected += 1
            self.log.error('%s handler failed: %s', event, e)
            return proto.reply(False, proto.BAD_PAYLOAD, str(e), cmd_id)
        self.accepted += 1
        self.events[event] = self.events.get(event, 0) + 1
        r = proto.reply(True, proto.OK, '', cmd_id)
        if extra:
            r.update(extra)
        return r

    def _drop_stale(self, event, cmd_id):
        """A set-point that waited in our input longer than the limit is not executed (a simulator
        starved of CPU would otherwise replay old motion), and costs almost nothing, so that a
        backlog drains; counted, no error event: the client cannot act on it and it would add load."""
        self.stale_targets += 1
        return proto.reply(False, proto.STALE, '%s older than %.3f s' % (event, self.max_target_age), cmd_id)

    def _stale(self, payload):
        """True for a set_target / set_clip older than max_target_age (sender time vs our wall clock)."""
        if self.max_target_age <= 0.0:
            return False
        try:
            t = proto.target_time(payload)
        except proto.ProtocolError:
            return False                 # parse_set_target reports it
        return t is not None and time.time() - t > self.max_target_age

    def _set_target(self, payload):
        cmd_id, pos, q = proto.parse_set_target(payload)
        self.model.set_target(pos, q, cmd_id)

    def _set_max_velocity(self, payload):
        _, v = proto.parse_set_max_velocity(payload)
        self.model.set_max_velocity(v)

    def _set_clip(self, payload):
        _, jaw, roll = proto.parse_set_clip(payload)
        self.model.set_clip(jaw, roll)

    def _hold(self, payload):
        proto.parse_hold(payload)
        self.model.hold()

    async def _on_subscribe_state(self, sid, payload=None):
        refusal = self._admit(sid, False)
        if refusal is not None:
            return proto.reply(False, refusal, 'refused')
        try:
            window = proto.parse_subscribe_state(payload)
        except proto.ProtocolError as e:
            self.rejected += 1
            return proto.reply(False, e.code, e.message)
        self.sio.enter_room(sid, proto.STATE_ROOM)
        self.subscribers.add(sid)
        if window > 0:
            self._flow[sid] = [window, 0, 0]
        else:
            self._flow.pop(sid, None)
        r = proto.reply(True)
        r['info'] = self.info()
        return r

    async def _on_state_ack(self, sid, payload=None):
        # no answer (sent ~30 times/s); a malformed one is counted and ignored
        if self._admit(sid, False) is not None:
            return
        try:
            received = proto.parse_state_ack(payload)
        except proto.ProtocolError:
            self.rejected += 1
            return
        flow = self._flow.get(sid)
        if flow is not None:
            flow[2] = max(flow[2], received)

    def _admit(self, sid, commanding):
        """SessionGate.admit; a flooding session is dropped (its events are refused meanwhile)."""
        refusal = self.gate.admit(sid, commanding)
        if refusal == 'flood':
            self.log.error('session %s floods (%d events over its rate limit within 1 s): dropped', sid,
                           self.gate.flood_limit)
            asyncio.ensure_future(self.sio.disconnect(sid))
            refusal = proto.RATE_LIMITED
        return refusal

    def _refused(self, sid, error):
        """Log a refused connection (one line per reason per second) and close its transport."""
        now = time.monotonic()
        if now - self._refusal_logged.get(error.reason, -1e9) >= 1.0:
            self._refusal_logged[error.reason] = now
            self.log.error('connection refused: %s (%d refused for this reason so far)', error,
                           self.gate.refused[error.reason])
        try:
            eio_sid = self.sio.manager.eio_sid_from_sid(sid, proto.NAMESPACE)
        except Exception:  # pylint: disable=broad-except
            return
        # after the CONNECT_ERROR went out: an unauthenticated transport gets nothing more
        asyncio.get_event_loop().call_later(0.05, lambda: asyncio.ensure_future(self.sio.eio.disconnect(eio_sid)))

    def info(self):
        m = self.model
        return {'version': proto.VERSION, 'joints': list(proto.MOTOR_JOINTS),
                'lower': [float(x) for x in m.lower], 'upper': [float(x) for x in m.upper],
                'insertion_ratio': m.insertion_ratio, 'max_velocity_limit': m.max_velocity_limit,
                'rate': self.rate, 'state_rate': self.state_rate}

    def state(self):
        m = self.model
        key = m.q.tobytes()
        if key != self._fk_key:        # forward kinematics only when the joints changed
            t = m.tip_in_base()
            self._fk = (t[:3, 3].copy(), matrix_to_quat(t[:3, :3]), m.rcm_position())
            self._fk_key = key
        self.state_seq += 1
        return proto.make_state(self.state_seq, self._sample_time, m.q, self._fk[0], self._fk[1],
                                self._fk[2], m.moving, m.max_velocity, m.target_id)

    def grid_behind(self):
        """[s] how far the state grid (next sample instant) is behind now (<= 0: on time)."""
        return time.monotonic() - self._deadline

    # ------------------------------------------------------------------ loop
    def advance(self, until=None):
        """Integrate the model up to ``until`` (monotonic time, default now) in sub-steps of at
        most 1/rate; a time in the model's past changes nothing."""
        t = time.monotonic() if until is None else until
        if t > self._last_step:
            self.model.step(t - self._last_step)
            self._last_step = t
            # wall-clock instant of this model state, on the same time base as the integration
            self._sample_time = t + self._wall_offset

    def _backlogged(self, sid):
        """True when the client's Engine.IO queue still holds max_backlog packets."""
        try:
            eio_sid = self.sio.manager.eio_sid_from_sid(sid, proto.NAMESPACE)
            sock = self.sio.eio.sockets.get(eio_sid)
        except Exception:  # pylint: disable=broad-except
            return False
        return sock is not None and sock.queue.qsize() >= self.max_backlog

    async def _sample_until(self):
        """Emit every sample of the ``state_rate`` grid up to now (taken once the emission lock is
        held) and return that time; each sample is integrated to its own instant and stamped with it. After a late wake-up (loaded host) the missed samples go out
        in a burst, as a robot controller on its own CPU would have sampled them; beyond
        ``max_catch_up`` periods the grid is re-anchored (those samples are lost, counted in
        ``missed``). Called by the control loop and before every command, so a command never
        overtakes samples owed before it and sample times always increase."""
        async with self._emit_lock:
            now = time.monotonic()
            period = self._period
            if now - self._deadline > self.max_catch_up * period:
                lost = int((now - self._deadline) / period)
                self.missed += lost
                self._deadline += lost * period
            while self._deadline <= now:
                self.advance(self._deadline)
                if self.subscribers:
                    await self._emit_state()
                self._deadline += period
        return now

    async def _emit_state(self):
        """One ``state`` sample to every subscriber that is not backlogged nor at its window. The
        Socket.IO packet is encoded once and queued on each client's Engine.IO socket: the same
        bytes as ``sio.emit(to=sid)``, without its JSON encoding per client and its task per emit
        (most of this server's CPU at 300 Hz x 2 clients)."""
        state, encoded = self.state(), None     # every sample has its seq, sent or skipped
        for sid in list(self.subscribers):
            flow = self._flow.get(sid)
            if self._backlogged(sid) or (flow is not None and flow[1] - flow[2] >= flow[0]):
                self.state_skipped += 1
                continue
            eio_sid = self.sio.manager.eio_sid_from_sid(sid, proto.NAMESPACE)
            if eio_sid is None:          # disconnected meanwhile (sio.emit would drop it too)
                continue
            if flow is not None:
                flow[1] += 1
            if encoded is None:
                encoded = self.sio.packet_class(socketio.packet.EVENT, namespace=proto.NAMESPACE,
                                                data=[proto.EV_STATE, state]).encode()
                encoded = encoded if isinstance(encoded, list) else [encoded]
            for ep in encoded:
                await self.sio.eio.send(eio_sid, ep)
            # as sio.emit did: let the client's writer task send it now (a queue put does not yield)
            await asyncio.sleep(0)

    async def _control(self):
        """Wake at the state rate and emit the samples that are due."""
        self._deadline = time.monotonic() + self._period
        while not self._stop.is_set():
            delay = self._deadline - time.monotonic()
            if delay > 0:
                await asyncio.sleep(delay)
            self.max_late = max(self.max_late, time.monotonic() - self._deadline)
            await self._sample_until()

    async def serve(self):
        self._stop = asyncio.Event()
        self._emit_lock = asyncio.Lock()
        runner = web.AppRunner(self.app)
        await runner.setup()
        site = web.TCPSite(runner, self.host, self.port, ssl_context=self.ssl_context)
        await site.start()
        self.log.info('SARAS arm server on %s:%d', self.host, self.port)
        self.ready.set()
        try:
            await self._control()
        finally:
            for sid in list(self.sids):          # orderly shutdown: tell the clients
                try:
                    await self.sio.disconnect(sid)
                except Exception:  # pylint: disable=broad-except
                    pass
            await runner.cleanup()

    def _set_realtime(self):
        """SCHED_FIFO at ``realtime_priority`` for the calling (server) thread only: the controller it
        stands in for has a CPU of its own; on a host shared with the platform a starved server
        answers a hold or a closed command link late. Without the right to: normal scheduling, warned."""
        if self.realtime_priority <= 0:
            return
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(self.realtime_priority))
            self.realtime = True
        except (OSError, AttributeError) as e:
            self.log.warning('cannot run the server thread at SCHED_FIFO %d (%s): normal scheduling',
                             self.realtime_priority, e)

    def run(self):
        """Serve until :meth:`stop` (blocking)."""
        self._set_realtime()
        self._loop = asyncio.new_event_loop()
        # the loop is this thread's current loop: aiohttp / engineio look it up while shutting down
        asyncio.set_event_loop(self._loop)
        try:
            self._loop.run_until_complete(self.serve())
        finally:
            pending = [t for t in asyncio.all_tasks(self._loop) if not t.done()]
            for t in pending:
                t.cancel()
            self._loop.run_until_complete(asyncio.gather(*pending, return_exceptions=True))
            self._loop.close()
            asyncio.set_event_loop(None)

    def start_in_thread(self, timeout=5.0):
        self._thread = threading.Thread(target=self.run, name='saras_arm_server', daemon=True)
        self._thread.start()
        if not self.ready.wait(timeout):
            raise RuntimeError('server did not start on %s:%d' % (self.host, self.port))

    def drop_clients(self, timeout=2.0):
        """Close every client connection from the server side (tests: a network drop)."""
        async def drop():
            for sid in list(self.sids):
                await self.sio.disconnect(sid)
        asyncio.run_coroutine_threadsafe(drop(), self._loop).result(timeout)

    def stop(self):
        if self._loop is not None and self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)
        if self._thread is not None:
            self._thread.join(5.0)
