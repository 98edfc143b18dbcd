"""User-space network impairment relay for UDP and TCP (asyncio, ROS-free).

This host's kernel has no ``netem`` qdisc, so links are impaired by relaying them: a sender sends to
the relay's ``listen`` address, the relay holds every datagram (or TCP chunk) for the delay its
:class:`~saras_bringup.netem.impairment.Impairment` draws, drops what the loss model drops, and
delivers to ``target`` (optionally from a fixed ``source`` address, so a receiver's whitelist sees
the sending machine's address). Replies travel back through the same relay with the link's
``reverse`` impairment. Counters per link direction are in :class:`LinkStats`.

UDP: one upstream socket per sender address (each sender's replies go back to it). TCP: one
upstream connection per accepted connection; chunks keep their order; the relay buffers in memory
what is in flight on the delayed link.
"""
import asyncio
import heapq
import itertools
import socket
import threading

from .impairment import Impairment, LinkStats

_MAX_DATAGRAM = 65535
_UDP_BUFFER = 4 * 1024 * 1024


class DelayLine:
    """Runs callbacks at given loop times; equal times keep their scheduling order."""

    def __init__(self, loop):
        self._loop = loop
        self._heap = []
        self._counter = itertools.count()
        self._timer = None

    def schedule(self, when, callback):
        heapq.heappush(self._heap, (when, next(self._counter), callback))
        if self._heap[0][2] is callback:
            self._arm()

    def _arm(self):
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self._loop.call_at(self._heap[0][0], self._fire) if self._heap else None

    def _fire(self):
        self._timer = None
        now = self._loop.time()
        while self._heap and self._heap[0][0] <= now:
            heapq.heappop(self._heap)[2]()
        self._arm()

    def cancel(self):
        if self._timer is not None:
            self._timer.cancel()
        self._heap.clear()


def _udp_socket(bind_addr):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, _UDP_BUFFER)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, _UDP_BUFFER)
    if bind_addr[1]:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind(bind_addr)
    sock.setblocking(False)
    return sock


class UdpLink:
    """Relays datagrams listen -> target (forward) and target -> sender (reverse)."""

    def __init__(self, config, loop, delay_line):
        self.config = config
        self.forward_stats, self.reverse_stats = LinkStats(), LinkStats()
        self._loop, self._delay = loop, delay_line
        seed = config.seed
        self._forward = Impairment(config.forward, seed)
        self._reverse = Impairment(config.reverse, None if seed is None else seed + 1)
        self._listen = None
        self._upstream = {}  # sender address (or 'fixed source') -> upstream socket
        self._reply_to = {}  # same key -> sender address replies go to

    def start(self):
        self._listen = _udp_socket(self.config.listen)
        self._loop.add_reader(self._listen, self._on_listen_readable)

    @property
    def listen_address(self):
        return self._listen.getsockname()

    def close(self):
        for sock in [self._listen] + list(self._upstream.values()):
            if sock is not None:
                self._loop.remove_reader(sock)
                sock.close()
        self._upstream.clear()

    def _upstream_for(self, sender):
        """The socket forwarding this sender's datagrams (shared with a fixed source port)."""
        fixed_port = self.config.source is not None and self.config.source[1] != 0
        key = 'fixed source' if fixed_port else sender
        sock = self._upstream.get(key)
        if sock is None:
            sock = _udp_socket(self.config.source or ('0.0.0.0', 0))
            self._loop.add_reader(sock, self._on_upstream_readable, sock, key)
            self._upstream[key] = sock
        self._reply_to[key] = sender  # with a fixed source port the latest sender gets replies
        return sock

    def _relay(self, data, impairment, stats, send):
        seq = stats.on_received()
        arrival = self._loop.time()
        release = impairment.datagram_release(arrival)
        if release is None:
            stats.on_dropped()
            return

        def deliver():
            try:
                send(data)
            except OSError:
                stats.on_dropped()
                return
            stats.on_sent(seq, self._loop.time() - arrival, len(data))
        self._delay.schedule(release, deliver)

    def _on_listen_readable(self):
        for _ in range(64):
            try:
                data, sender = self._listen.recvfrom(_MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            upstream = self._upstream_for(sender)
            target = self.config.target
            self._relay(data, self._forward, self.forward_stats,
                        lambda d, s=upstream: s.sendto(d, target))

    def _on_upstream_readable(self, sock, key):
        for _ in range(64):
            try:
                data, _ = sock.recvfrom(_MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            self._relay(data, self._reverse, self.reverse_stats,
                        lambda d, o=self._reply_to[key]: self._listen.sendto(d, o))


class TcpLink:
    """Relays TCP connections listen -> target; chunks delayed and jittered, order kept."""

    def __init__(self, config, loop, delay_line):
        self.config = config
        self.forward_stats, self.reverse_stats = LinkStats(), LinkStats()
        self._loop, self._delay = loop, delay_line
        self._server = None
        self._connections = itertools.count()
        self._writers = set()

    async def start(self):
        host, port = self.config.listen
        self._server = await asyncio.start_server(self._on_connection, host, port,
                                                  reuse_address=True)

    @property
    def listen_address(self):
        return self._server.sockets[0].getsockname()[:2]

    def close(self):
        if self._server is not None:
            self._server.close()
        for writer in list(self._writers):
            writer.close()

    def _seed(self, n, direction):
        return None if self.config.seed is None else self.config.seed + 2 * n + direction

    async def _on_connection(self, reader, writer):
        n = next(self._connections)
        host, port = self.config.target
        local = (self.config.source[0], 0) if self.config.source else None
        try:
            up_reader, up_writer = await asyncio.open_connection(host, port, local_addr=local)
        except OSError:
            writer.close()
            return
        self._writers.update((writer, up_writer))
        forward = Impairment(self.config.forward, self._seed(n, 0))
        reverse = Impairment(self.config.reverse, self._seed(n, 1))
        ends = await asyncio.gather(self._pump(reader, up_writer, forward, self.forward_stats),
                                    self._pump(up_reader, writer, reverse, self.reverse_stats))
        self._delay.schedule(max(ends), lambda: self._close(writer, up_writer))

    async def _pump(self, reader, writer, impairment, stats):
        """Relays one direction until EOF; returns the time its EOF is passed on."""
        last = self._loop.time()
        while True:
            try:
                chunk = await reader.read(65536)
            except (ConnectionError, OSError):
                chunk = b''
            arrival = self._loop.time()
            if not chunk:
                end = max(last, arrival)
                self._delay.schedule(end, lambda: self._write_eof(writer))
                return end
            seq = stats.on_received()
            last = impairment.stream_release(arrival)

            def deliver(data=chunk, seq=seq, arrival=arrival):
                if not writer.is_closing():
                    writer.write(data)
                    stats.on_sent(seq, self._loop.time() - arrival, len(data))
            self._delay.schedule(last, deliver)

    @staticmethod
    def _write_eof(writer):
        """Passes a half-close on (the other direction may still be running)."""
        if writer.is_closing():
            return
        try:
            if writer.can_write_eof():
                writer.write_eof()
                return
        except OSError:
            pass
        writer.close()

    def _close(self, *writers):
        for writer in writers:
            writer.close()
            self._writers.discard(writer)


class Relay:
    """All links of a links file on one event loop."""

    def __init__(self, links, loop=None):
        self.loop = loop or asyncio.get_event_loop()
        self._delay = DelayLine(self.loop)
        self.links = [(UdpLink if c.protocol == 'udp' else TcpLink)(c, self.loop, self._delay)
                      for c in links]

    async def start(self):
        for link in self.links:
            if isinstance(link, TcpLink):
                await link.start()
            else:
                link.start()

    def close(self):
        for link in self.links:
            link.close()
        self._delay.cancel()

    def addresses(self):
        """{link name: (host, port) it listens on} (resolves a configured port 0)."""
        return {link.config.name: link.listen_address for link in self.links}

    def stats(self):
        """{link name: {'forward': counters, 'reverse': counters}}."""
        return {link.config.name: {'forward': link.forward_stats.as_dict(),
                                   'reverse': link.reverse_stats.as_dict()}
                for link in self.links}


class RelayThread:
    """A Relay on its own event loop in a background thread (for harnesses and tests)."""

    def __init__(self, links):
        self._links = links
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)
        self.relay = None

    def __enter__(self):
        self._thread.start()
        self.relay = self._call(self._make())
        return self

    async def _make(self):
        relay = Relay(self._links, self._loop)
        await relay.start()
        return relay

    def _call(self, coroutine, timeout=10.0):
        return asyncio.run_coroutine_threadsafe(coroutine, self._loop).result(timeout)

    def stats(self):
        async def read():
            return self.relay.stats()
        return self._call(read())

    def addresses(self):
        async def read():
            return self.relay.addresses()
        return self._call(read())

    def __exit__(self, *exc):
        async def close():
            self.relay.close()
        self._call(close())
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(10.0)
        self._loop.close()
