"""Socket.IO server of one simulated SARAS arm (ROS-agnostic core of ``saras_arm_sim``).

python-socketio ``AsyncServer`` on aiohttp, one asyncio loop per arm:

* a control task integrates :class:`SarasArmModel` at ``rate`` Hz (>= 500 Hz) using the measured
  elapsed time (so a late wake-up is integrated, not lost), and every ``rate/state_rate`` steps
  emits a ``state`` event to the clients that subscribed;
* event handlers validate payloads with :mod:`saras_arm_protocol` and answer with an ack; a rejected
  command also gets an ``error`` event and changes nothing;
* when the client that commanded motion disconnects, the arm holds (target := current joints).
"""

import asyncio
import logging
import threading
import time

import socketio
from aiohttp import web

from saras_drivers import saras_arm_protocol as proto
from saras_drivers.saras_arm_model import matrix_to_quat


class SarasArmServer(object):
    """:param model: :class:`SarasArmModel`; :param rate: integration rate [Hz];
    :param state_rate: state stream rate [Hz] (rate must be a multiple)."""

    def __init__(self, model, host='127.0.0.1', port=5000, rate=1000.0, state_rate=250.0,
                 logger=None, ping_interval=1.0, ping_timeout=1.0):
        if not rate >= 500.0:
            raise ValueError('rate must be >= 500 Hz, got %r' % rate)
        if not 0.0 < state_rate <= rate:
            raise ValueError('state_rate must be in (0, rate], got %r' % state_rate)
        self.model = model
        self.host, self.port = host, int(port)
        self.rate = float(rate)
        self.decimation = max(1, int(round(rate / state_rate)))
        self.log = logger or logging.getLogger('saras_arm_server')
        # Engine.IO heartbeat: a client that misses pings for ping_interval + ping_timeout [s] is
        # dropped (and a client detects a dead server in the same time).
        self.sio = socketio.AsyncServer(async_mode='aiohttp', logger=False, engineio_logger=False,
                                        ping_interval=ping_interval, ping_timeout=ping_timeout)
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
        self._sample_time = time.time()
        self._wall_offset = time.time() - time.monotonic()
        self.ready = threading.Event()
        self._stop = None
        self._loop = None
        self._thread = None
        self._register()

    # ------------------------------------------------------------------ handlers
    def _register(self):
        sio = self.sio

        @sio.event
        async def connect(sid, environ):
            self.clients += 1
            self.sids.add(sid)
            self.log.info('client %s connected', sid)

        @sio.event
        async def disconnect(sid):
            self.clients -= 1
            self.sids.discard(sid)
            if sid == self.commander:
                self.model.hold()
                self.commander = None
                self.log.warning('commanding client %s disconnected: holding', sid)

        async def run(sid, event, payload, fn):
            cmd_id = payload.get('id', 0) if isinstance(payload, dict) else 0
            cmd_id = cmd_id if isinstance(cmd_id, int) and not isinstance(cmd_id, bool) else 0
            try:
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

        def set_target(payload):
            cmd_id, pos, q = proto.parse_set_target(payload)
            self.model.set_target(pos, q, cmd_id)

        def set_max_velocity(payload):
            _, v = proto.parse_set_max_velocity(payload)
            self.model.set_max_velocity(v)

        def set_clip(payload):
            _, jaw, roll = proto.parse_set_clip(payload)
            self.model.set_clip(jaw, roll)

        def hold(payload):
            proto.parse_hold(payload)
            self.model.hold()

        def commanding(fn):
            async def handler(sid, payload=None):
                r = await run(sid, fn.__name__, payload, fn)
                if r['ok']:
                    self.commander = sid
                return r
            return handler

        for fn in (set_target, set_max_velocity, set_clip, hold):
            sio.on(fn.__name__, commanding(fn))

        @sio.on(proto.EV_SUBSCRIBE_STATE)
        async def subscribe_state(sid, payload=None):
            self.sio.enter_room(sid, proto.STATE_ROOM)
            r = proto.reply(True)
            r['info'] = self.info()
            return r

    def info(self):
        m = self.model
        return {'version': proto.VERSION, 'joints': list(proto.MOTOR_JOINTS),
                'lower': [float(x) for x in m.lower], 'upper': [float(x) for x in m.upper],
                'insertion_ratio': m.insertion_ratio, 'max_velocity_limit': m.max_velocity_limit,
                'rate': self.rate, 'state_rate': self.rate / self.decimation}

    def state(self):
        m = self.model
        t = m.tip_in_base()
        self.state_seq += 1
        return proto.make_state(self.state_seq, self._sample_time, m.q, t[:3, 3], matrix_to_quat(t[:3, :3]),
                                m.rcm_position(), m.moving, m.max_velocity, m.target_id)

    # ------------------------------------------------------------------ loop
    async def _control(self):
        period = 1.0 / self.rate
        last = time.monotonic()
        deadline = last + period
        k = 0
        while not self._stop.is_set():
            delay = deadline - time.monotonic()
            if delay > 0:
                await asyncio.sleep(delay)
            now = time.monotonic()
            # wall-clock instant of this model state, on the same time base as the integration
            self._sample_time = now + self._wall_offset
            self.max_late = max(self.max_late, now - deadline)
            self.model.step(now - last)
            last = now
            k += 1
            if k % self.decimation == 0:
                await self.sio.emit(proto.EV_STATE, self.state(), room=proto.STATE_ROOM)
            deadline += period
            if now - deadline > 10 * period:      # overloaded: re-anchor instead of bursting
                deadline = now + period

    async def serve(self):
        self._stop = asyncio.Event()
        runner = web.AppRunner(self.app)
        await runner.setup()
        site = web.TCPSite(runner, self.host, self.port)
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

    def run(self):
        """Serve until :meth:`stop` (blocking)."""
        self._loop = asyncio.new_event_loop()
        try:
            self._loop.run_until_complete(self.serve())
        finally:
            pending = [t for t in asyncio.all_tasks(self._loop) if not t.done()]
            for t in pending:
                t.cancel()
            self._loop.run_until_complete(asyncio.gather(*pending, return_exceptions=True))
            self._loop.close()

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
