"""Console side of the Touchball protocol v2 session (ROS-free): handshake, state packets, command
validation. Used by the console simulator, the tests and the benchmarks; the Windows controller
implements the same rules (``docs/touchball_protocol.md``, "Handshake").

* Unbound, the console sends a HELLO with its random nonce every ``hello_interval`` [s] instead of
  state packets.
* A CHALLENGE with a valid tag that echoes the current console nonce binds the session: state
  packets then carry its nonce and a sequence number that increases by one per packet.
* COMMAND packets are accepted only with a valid tag, the bound session and a newer sequence
  number; anything else is counted per reason and ignored.
* No valid command for ``rebind_after`` [s] while bound (receiver restarted, link lost): the
  session is dropped and a new handshake starts with a new console nonce.
"""

import secrets

from saras_drivers import touchball_protocol as tp


def random_nonce():
    """A random, non-zero 64-bit nonce."""
    while True:
        n = secrets.randbits(64)
        if n:
            return n


class ConsoleSession(object):
    """:param mac: :class:`touchball_protocol.Mac` of the deployment key."""

    def __init__(self, mac, hello_interval=0.1, rebind_after=1.0, nonce_source=random_nonce):
        if not hello_interval > 0.0 or not rebind_after > 0.0:
            raise ValueError('hello_interval and rebind_after must be > 0 s')
        self.mac = mac
        self.hello_interval = float(hello_interval)
        self.rebind_after = float(rebind_after)
        self._nonce_source = nonce_source
        self.console_nonce = nonce_source()
        self.session = None              # bound session nonce
        self.seq = 0
        self._last_hello = None
        self._alive = None               # time of the binding or of the last valid command
        self._commands = tp.SequenceTracker()
        self.commands = (tp.ZERO_COMMAND, tp.ZERO_COMMAND)
        self.command_time = None         # time of the last valid command
        self.commands_received = 0
        self.sessions = 0
        self.rejected = {}               # reason -> count of refused datagrams from the ROS side

    @property
    def bound(self):
        return self.session is not None

    def _next_seq(self):
        s = self.seq
        self.seq = (self.seq + 1) & 0xFFFFFFFF
        return s

    def check_alive(self, now):
        """Drop a session without a valid command for ``rebind_after`` (starts a new handshake)."""
        if self.session is not None and now - self._alive > self.rebind_after:
            self.session = None
            self.console_nonce = self._nonce_source()
            self._last_hello = None

    def outgoing(self, devices, sender_time, now):
        """The datagram to send now: a state packet when bound, else a hello when one is due, else None."""
        self.check_alive(now)
        if self.session is not None:
            return tp.pack_state(self.mac, self.session, self._next_seq(), sender_time, devices)
        if self._last_hello is None or now - self._last_hello >= self.hello_interval:
            self._last_hello = now
            return tp.pack_hello(self.mac, self.console_nonce, self._next_seq(), sender_time)
        return None

    def _reject(self, reason):
        self.rejected[reason] = self.rejected.get(reason, 0) + 1
        return None

    def handle(self, data, now):
        """Validate a datagram from the ROS side. Returns 'challenge' (session bound), 'command'
        (stored in :attr:`commands`) or None (refused, counted in :attr:`rejected`)."""
        data = bytes(data)
        if len(data) >= 6 and data[5] == tp.TYPE_CHALLENGE:
            try:
                c = tp.unpack_challenge(data, self.mac)
            except tp.ProtocolError as e:
                return self._reject(e.reason)
            if c.console_nonce != self.console_nonce or self.session is not None:
                return self._reject('session')       # not an answer to our current hello
            self.session = c.session
            self._alive = now
            self._commands.reset()
            self.sessions += 1
            return 'challenge'
        try:
            if self.session is None:
                raise tp.ProtocolError('session', 'no session bound')
            pkt = tp.unpack_command(data, self.mac, self.session)
            self._commands.accept(pkt.seq)
        except tp.ProtocolError as e:
            return self._reject(e.reason)
        self.commands = pkt.devices
        self.command_time = now
        self._alive = now
        self.commands_received += 1
        return 'command'

    @property
    def commands_rejected(self):
        return sum(self.rejected.values())
