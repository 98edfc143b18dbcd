"""Read-only HTTP server of the operator view (Python stdlib ``http.server``, ROS-free).

Routes (GET and HEAD only; every other method is 405, unknown paths 404, malformed requests 400):

  /, /index.html          the page (page.py), no external resources
  /app.js                 its script
  /state.json             one payload (LiveState.snapshot)
  /events                 Server-Sent Events: the payload every ``update_period``
  /stream/<eye>.mjpg      multipart/x-mixed-replace of the eye's JPEG frames as received (no re-encoding)
  /frame/<eye>.jpg        the eye's newest JPEG (404 before the first frame)
  /favicon.ico            204 (no icon)

A request whose Host header names a host outside ``allowed_hosts`` (plus the loopback names and
the bind address) is refused with 403, so that a web page elsewhere cannot read the stream through
DNS rebinding.

The image streams count as viewers: ``on_viewers(n)`` is called whenever the number of open image
streams goes from 0 to 1 or back to 0, so the node subscribes to the images only while a browser
shows them. Likewise the event streams count as pages: ``on_pages(n)`` is called when the first page
opens its event stream (n = 1) and when the last closes (n = 0), so that the node subscribes to the
1 kHz tank energies only while a page shows them (/state.json alone reports them stale). Long-lived connections (streams and events) are limited to ``max_clients``; a client
that stops reading is dropped after ``client_timeout``.
"""
import json
import select
import socket
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import urlsplit

from saras_operator_view import page

EYES = ('left', 'right')
_STATIC = {'/': ('page', 'text/html; charset=utf-8'), '/index.html': ('page', 'text/html; charset=utf-8'),
           '/app.js': ('script', 'application/javascript; charset=utf-8')}
_CSP = "default-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self'; connect-src 'self'"
BOUNDARY = b'saras-frame'


def route(raw_path):
    """(kind, argument) for a request target, or None (404). Query and fragment are ignored."""
    try:
        path = urlsplit(raw_path).path
    except ValueError:
        return None
    if path in _STATIC:
        return ('static', path)
    if path == '/state.json':
        return ('state', None)
    if path == '/events':
        return ('events', None)
    if path == '/favicon.ico':
        return ('empty', None)
    for eye in EYES:
        if path == '/stream/%s.mjpg' % eye:
            return ('stream', eye)
        if path == '/frame/%s.jpg' % eye:
            return ('frame', eye)
    return None


def host_name(header):
    """Host name of a Host header value, lower case, without port or IPv6 brackets ('' if unset)."""
    value = (header or '').strip().lower()
    if value.startswith('['):
        return value[1:value.find(']')] if ']' in value else value[1:]
    return value.rsplit(':', 1)[0] if value.count(':') == 1 else value


def mjpeg_part(jpeg):
    """One multipart part: headers, the JPEG bytes unchanged, then the next boundary (a browser
    shows a part once the boundary after it arrived)."""
    return (b'Content-Type: image/jpeg\r\nContent-Length: %d\r\n\r\n' % len(jpeg) + jpeg +
            b'\r\n--' + BOUNDARY + b'\r\n')


def to_json(payload):
    """``payload`` as compact JSON bytes (never NaN: the payload holds null for unknown values)."""
    return json.dumps(payload, allow_nan=False, separators=(',', ':')).encode()


def sse_event(payload):
    """One Server-Sent Event carrying ``payload`` as JSON."""
    return b'data: ' + to_json(payload) + b'\n\n'


class Counters(object):
    """Request statistics for /diagnostics (thread-safe)."""

    def __init__(self):
        self._lock = threading.Lock()
        self.values = {'requests': 0, 'bad requests': 0, 'refused (too many clients)': 0, 'frames sent': 0}

    def add(self, key, n=1):
        with self._lock:
            self.values[key] += n

    def copy(self):
        with self._lock:
            return dict(self.values)


class OperatorViewServer(object):
    """The HTTP server, started in a thread by :meth:`start`."""

    def __init__(self, live, bind_address, port, update_period=0.2, max_clients=8, max_stream_rate=30.0,
                 client_timeout=10.0, clock=time.monotonic, on_viewers=None, title='SARAS operator view',
                 on_pages=None,
                 allowed_hosts=()):
        self.live = live
        self.update_period = float(update_period)
        self.max_clients = int(max_clients)
        self.min_frame_interval = 1.0 / float(max_stream_rate)
        self.clock = clock
        self.on_viewers = on_viewers
        self.on_pages = on_pages
        self.counters = Counters()
        # Host names a browser may use for this page; any other is refused (DNS rebinding: a web
        # page elsewhere resolving its own name to this address cannot read the stream)
        self.allowed_hosts = {'127.0.0.1', 'localhost', '::1', bind_address.lower()} | {h.lower() for h in allowed_hosts}
        self.html = page.html(title).encode()
        self.script = page.SCRIPT.encode()
        self._lock = threading.Lock()
        self._viewer_lock = threading.Lock()
        self._clients = 0
        self._viewers = 0
        self._pages = 0
        self._stop = threading.Event()
        handler = type('Handler', (_Handler,), {'view': self, 'timeout': float(client_timeout)})
        family = socket.AF_INET6 if ':' in bind_address else socket.AF_INET
        server = type('Server', (ThreadingHTTPServer,), {'address_family': family})
        self.httpd = server((bind_address, int(port)), handler)
        self.httpd.daemon_threads = True
        self._thread = None

    @property
    def address(self):
        """(host, port) actually bound (port 0 picks a free one)."""
        return self.httpd.server_address[:2]

    def start(self):
        self._thread = threading.Thread(target=self.httpd.serve_forever, kwargs={'poll_interval': 0.2},
                                        name='operator_view_http', daemon=True)
        self._thread.start()

    def stop(self):
        self._stop.set()
        self.live.close()
        self.httpd.shutdown()
        self.httpd.server_close()

    @property
    def stopping(self):
        return self._stop.is_set()

    def wait(self, seconds):
        """Sleep ``seconds`` unless the server stops; True if it stops."""
        return self._stop.wait(seconds)

    def snapshot(self):
        return self.live.snapshot(self.clock())

    def clients(self):
        """(long-lived connections, image streams) now open."""
        with self._lock:
            clients = self._clients
        with self._viewer_lock:
            return clients, self._viewers

    def acquire(self, image):
        """Admit one long-lived connection (an image stream if ``image``); False when full. The first
        image stream calls ``on_viewers(1)``; the count and the call are one step, so that a stream
        closing at the same time cannot reorder subscribe and unsubscribe."""
        with self._lock:
            if self._clients >= self.max_clients:
                return False
            self._clients += 1
        with self._viewer_lock:
            if image:
                self._viewers += 1
                if self._viewers == 1 and self.on_viewers:
                    self.on_viewers(1)
            else:
                self._pages += 1
                if self._pages == 1 and self.on_pages:
                    self.on_pages(1)
        return True

    def release(self, image):
        """End a connection admitted by :meth:`acquire`; the last image stream calls ``on_viewers(0)``,
        the last event stream ``on_pages(0)``."""
        with self._viewer_lock:
            if image:
                self._viewers -= 1
                if self._viewers == 0 and self.on_viewers:
                    self.on_viewers(0)
            else:
                self._pages -= 1
                if self._pages == 0 and self.on_pages:
                    self.on_pages(0)
        with self._lock:
            self._clients -= 1


class _Handler(BaseHTTPRequestHandler):
    """One request; ``view`` (OperatorViewServer) is set on the subclass the server builds."""
    view = None
    server_version = 'SarasOperatorView/1'
    sys_version = ''
    protocol_version = 'HTTP/1.0'

    def log_message(self, fmt, *args):  # no access log on stderr; errors are counted
        pass

    def send_error(self, code, message=None, explain=None):
        self.view.counters.add('bad requests')
        if code == 405:
            self._allow = True
        BaseHTTPRequestHandler.send_error(self, code, message, explain)

    def end_headers(self):
        if getattr(self, '_allow', False):
            self.send_header('Allow', 'GET, HEAD')
        self.send_header('X-Content-Type-Options', 'nosniff')
        self.send_header('Content-Security-Policy', _CSP)
        self.send_header('Cache-Control', 'no-store')
        BaseHTTPRequestHandler.end_headers(self)

    def do_GET(self):
        self._serve(body=True)

    def do_HEAD(self):
        self._serve(body=False)

    def _refuse_method(self):
        self.send_error(405, 'read-only: GET and HEAD only')

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = do_CONNECT = do_TRACE = _refuse_method

    def _serve(self, body):
        self.view.counters.add('requests')
        host = self.headers.get('Host')
        if host is not None and host_name(host) not in self.view.allowed_hosts:
            self.send_error(403, 'unknown host name (allowed_hosts)')
            return
        target = route(self.path)
        if target is None:
            self.send_error(404)
            return
        kind, arg = target
        try:
            if kind == 'static':
                self._send(200, _STATIC[arg][1], self.view.html if _STATIC[arg][0] == 'page' else self.view.script, body)
            elif kind == 'empty':
                self._send(204, 'text/plain', b'', False)
            elif kind == 'state':
                self._send(200, 'application/json', to_json(self.view.snapshot()), body)
            elif kind == 'frame':
                _, jpeg, _ = self.view.live.frames[arg].latest()
                if jpeg is None:
                    self.send_error(404, 'no %s frame yet' % arg)
                else:
                    self._send(200, 'image/jpeg', jpeg, body)
            elif not body:
                self._send(200, 'text/event-stream' if kind == 'events' else 'multipart/x-mixed-replace', b'', False)
            else:
                self._long_lived(kind, arg)
        except (ConnectionError, socket.timeout, OSError):
            self.close_connection = True

    def _send(self, code, ctype, data, body):
        self.send_response(code)
        self.send_header('Content-Type', ctype)
        self.send_header('Content-Length', str(len(data)))
        self.end_headers()
        if body:
            self.wfile.write(data)

    def _long_lived(self, kind, eye):
        image = kind == 'stream'
        if not self.view.acquire(image):
            self.view.counters.add('refused (too many clients)')
            self.send_error(503, 'too many clients')
            return
        try:
            self.send_response(200)
            if image:
                self.send_header('Content-Type', 'multipart/x-mixed-replace; boundary=' + BOUNDARY.decode())
            else:
                self.send_header('Content-Type', 'text/event-stream')
            self.end_headers()
            if image:
                self._stream_frames(self.view.live.frames[eye])
            else:
                self._stream_events()
        finally:
            self.view.release(image)

    def _stream_frames(self, slot):
        self.wfile.write(b'--' + BOUNDARY + b'\r\n')
        count = 0
        while not self.view.stopping:
            got = slot.wait_newer(count, 1.0)
            if got is None:
                if self._client_gone():
                    break
                continue
            count, jpeg = got
            sent = time.monotonic()
            self.wfile.write(mjpeg_part(jpeg))
            self.wfile.flush()
            self.view.counters.add('frames sent')
            rest = self.view.min_frame_interval - (time.monotonic() - sent)
            if rest > 0 and self.view.wait(rest):
                break

    def _client_gone(self):
        """True when the client closed its end (checked while no frame arrives, so that a closed
        page unsubscribes the images even when nothing is written to it)."""
        try:
            ready, _, _ = select.select([self.connection], [], [], 0)
            return bool(ready) and self.connection.recv(1, socket.MSG_PEEK) == b''
        except (OSError, ValueError):
            return True

    def _stream_events(self):
        self.wfile.write(b'retry: 1000\n\n')
        while not self.view.stopping:
            self.wfile.write(sse_event(self.view.snapshot()))
            self.wfile.flush()
            if self.view.wait(self.view.update_period):
                break
