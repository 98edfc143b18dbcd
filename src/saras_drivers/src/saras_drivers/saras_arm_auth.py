"""Authentication and flood control of the SARAS arm Socket.IO link (ROS-free).

Connect ``auth`` payload (``docs/saras_arm_protocol.md``, "Authentication")::

    {"v": 1, "arm": "mesa_left", "role": "command" | "monitor", "time": <sender wall clock, s>,
     "nonce": <32 hex digits, random>, "mac": <64 hex digits>}

``mac`` = HMAC-SHA256(key, "saras-arm-auth/1" NUL arm NUL role NUL time (repr) NUL nonce), the key
being the deployment key of the arm link (``saras_drivers.keys``). The server accepts a payload
whose MAC verifies, whose ``arm`` is its own, whose ``time`` is within ``max_skew`` of its clock and
whose nonce it has not seen within that window (a captured payload cannot be replayed). The key is
never sent. Unauthenticated connections are refused before any event is handled.
"""

import hashlib
import hmac
import math
import secrets
import time

AUTH_VERSION = 1
ROLES = ('command', 'monitor')
_CONTEXT = b'saras-arm-auth/1'


class AuthError(ValueError):
    """A refused connection; ``reason`` is one of :data:`AUTH_REASONS`."""

    def __init__(self, reason, detail=''):
        super(AuthError, self).__init__('%s: %s' % (reason, detail) if detail else reason)
        self.reason = reason


AUTH_REASONS = ('missing', 'malformed', 'arm', 'mac', 'expired', 'replayed')


def _mac(key, arm, role, t, nonce):
    msg = b'\0'.join((_CONTEXT, arm.encode(), role.encode(), repr(float(t)).encode(), nonce.encode()))
    return hmac.new(key, msg, hashlib.sha256).hexdigest()


def make_auth(key, arm, role, now=None, nonce=None):
    """The connect ``auth`` payload of a client of ``arm`` (e.g. 'mesa_left') in ``role``."""
    if role not in ROLES:
        raise ValueError('role must be one of %s' % (ROLES,))
    t = time.time() if now is None else float(now)
    nonce = secrets.token_hex(16) if nonce is None else nonce
    return {'v': AUTH_VERSION, 'arm': arm, 'role': role, 'time': t, 'nonce': nonce,
            'mac': _mac(key, arm, role, t, nonce)}


class Authenticator(object):
    """Server side: checks connect payloads of ``arm``; ``max_skew`` [s] bounds the clock
    difference and the replay window (nonces are remembered that long)."""

    def __init__(self, key, arm, max_skew=30.0):
        if not max_skew > 0.0:
            raise ValueError('max_skew must be > 0 s')
        self.key, self.arm, self.max_skew = bytes(key), arm, float(max_skew)
        self._seen = {}                  # nonce -> its time

    def check(self, auth, now=None):
        """The role of a valid payload; raises :class:`AuthError`."""
        now = time.time() if now is None else now
        if not auth:
            raise AuthError('missing', 'no auth payload')
        if not isinstance(auth, dict) or set(auth) != {'v', 'arm', 'role', 'time', 'nonce', 'mac'}:
            raise AuthError('malformed', 'auth must be an object with v, arm, role, time, nonce, mac')
        t, nonce, mac = auth['time'], auth['nonce'], auth['mac']
        if (auth['v'] != AUTH_VERSION or auth['role'] not in ROLES or not isinstance(auth['arm'], str)
                or isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t)
                or not isinstance(nonce, str) or not 16 <= len(nonce) <= 64
                or not isinstance(mac, str) or len(mac) != 64):
            raise AuthError('malformed', 'field types')
        if auth['arm'] != self.arm:
            raise AuthError('arm', 'payload for %r, this is %r' % (auth['arm'], self.arm))
        if not hmac.compare_digest(_mac(self.key, auth['arm'], auth['role'], t, nonce), mac):
            raise AuthError('mac', 'wrong key or altered payload')
        if abs(now - t) > self.max_skew:
            raise AuthError('expired', 'time off by %.1f s (clocks must agree within %.0f s)'
                            % (now - t, self.max_skew))
        for n, seen in list(self._seen.items()):
            if now - seen > 2.0 * self.max_skew:
                del self._seen[n]
        if nonce in self._seen:
            raise AuthError('replayed', 'nonce already used')
        self._seen[nonce] = t
        return auth['role']


class TokenBucket(object):
    """Event rate limit of one session: ``rate`` [events/s] sustained, ``burst`` at once."""

    def __init__(self, rate, burst, now=None):
        if not rate > 0.0 or not burst >= 1:
            raise ValueError('rate must be > 0 and burst >= 1')
        self.rate, self.burst = float(rate), float(burst)
        self.tokens = self.burst
        self.t = time.monotonic() if now is None else now

    def allow(self, now=None):
        now = time.monotonic() if now is None else now
        self.tokens = min(self.burst, self.tokens + (now - self.t) * self.rate)
        self.t = now
        if self.tokens >= 1.0:
            self.tokens -= 1.0
            return True
        return False


class SessionGate(object):
    """Server-side admission of Socket.IO sessions and their events (the simulator's, and the
    reference for the robot's server):

    * :meth:`connect` authenticates a session (:class:`Authenticator`); refused => counted per reason;
    * the newest authenticated ``command`` session is the only one whose commands may move the arm;
      an older one is stale (:meth:`connect` returns it so the server holds and drops it);
    * :meth:`admit` rate-limits the events of every session (:class:`TokenBucket`), counted; a
      session with ``flood_limit`` events refused by the rate limit within one second is a flood: :meth:`admit` returns 'flood' and
      the server drops it (each refused event still costs the server its decoding).
    """

    def __init__(self, authenticator, event_rate=1000.0, event_burst=200, flood_limit=500):
        self.auth = authenticator
        self.event_rate, self.event_burst = float(event_rate), int(event_burst)
        TokenBucket(self.event_rate, self.event_burst)             # validates
        self.roles = {}                  # sid -> role
        self._buckets = {}
        self.flood_limit = int(flood_limit)
        self._over = {}                  # sid -> [window start, events refused by the rate limit in it]
        self.command_sid = None
        self.floods = 0                  # sessions dropped for flooding
        self.refused = dict((r, 0) for r in AUTH_REASONS)          # connections refused per reason
        self.rate_limited = 0            # events dropped by the rate limit
        self.not_commander = 0           # commands from a session that may not command
        self.superseded = 0              # command sessions replaced by a newer one

    def connect(self, sid, auth, now=None):
        """Admit session ``sid``; returns the superseded command session (or None). Raises
        :class:`AuthError` (counted) for an unauthenticated one."""
        try:
            role = self.auth.check(auth, now)
        except AuthError as e:
            self.refused[e.reason] += 1
            raise
        self.roles[sid] = role
        self._buckets[sid] = TokenBucket(self.event_rate, self.event_burst)
        old = None
        if role == 'command':
            if self.command_sid is not None and self.command_sid != sid:
                old = self.command_sid
                self.superseded += 1
            self.command_sid = sid
        return old

    def disconnect(self, sid):
        self.roles.pop(sid, None)
        self._buckets.pop(sid, None)
        self._over.pop(sid, None)
        if sid == self.command_sid:
            self.command_sid = None

    def admit(self, sid, commanding, now=None):
        """None if the event may be handled, else the refusal code (counted)."""
        bucket = self._buckets.get(sid)
        if bucket is None:
            self.not_commander += 1
            return 'not_commander'
        now = time.monotonic() if now is None else now
        if not bucket.allow(now):
            self.rate_limited += 1
            window = self._over.setdefault(sid, [now, 0])
            if now - window[0] > 1.0:
                window[:] = [now, 0]
            window[1] += 1
            if window[1] == self.flood_limit:
                self.floods += 1
                return 'flood'
            return 'rate_limited'
        if commanding and sid != self.command_sid:
            self.not_commander += 1
            return 'not_commander'
        return None

    def counters(self):
        """Key/values for /diagnostics."""
        d = dict(('refused %s' % r, n) for r, n in self.refused.items())
        d.update({'events rate-limited': self.rate_limited, 'commands not from the commander': self.not_commander,
                  'command sessions superseded': self.superseded, 'sessions': len(self.roles),
                  'sessions dropped (flood)': self.floods})
        return d
