"""saras_operator_view.server: routing, read-only methods, bad requests, MJPEG and SSE streams,
lazy image subscription (real sockets on loopback, no ROS)."""
import http.client
import json
import re
import socket
import threading
import time

import pytest

from saras_operator_view.live import LiveState
from saras_operator_view.server import BOUNDARY, OperatorViewServer, route

THR = {'collision': 0.005, 'warning': 0.02}
COL = {'collision': '#ff0000', 'warning': '#ffff00', 'safe': '#00ff00', 'unknown': '#a0a0a0'}
TIMEOUT = 30.0


@pytest.mark.parametrize('path, expected', [
    ('/', ('static', '/')), ('/index.html', ('static', '/index.html')), ('/app.js', ('static', '/app.js')),
    ('/state.json?x=1', ('state', None)), ('/events', ('events', None)),
    ('/stream/left.mjpg', ('stream', 'left')), ('/stream/right.mjpg?t=5', ('stream', 'right')),
    ('/frame/right.jpg', ('frame', 'right')), ('/stream/middle.mjpg', None), ('/../etc/passwd', None),
    ('/favicon.ico', ('empty', None)), ('/state.json/', None), ('', None), ('http://[bad', None)])
def test_routes(path, expected):
    assert route(path) == expected


class Viewers(object):
    def __init__(self):
        self.calls = []
        self.cond = threading.Condition()

    def __call__(self, n):
        with self.cond:
            self.calls.append(n)
            self.cond.notify_all()

    def wait(self, calls):
        with self.cond:
            return self.cond.wait_for(lambda: self.calls == calls, TIMEOUT)


@pytest.fixture
def served():
    live = LiveState(THR, COL, ['tank_master', 'tank_slave'], 2.0)
    viewers, pages = Viewers(), Viewers()
    srv = OperatorViewServer(live, '127.0.0.1', 0, update_period=0.05, max_clients=3, on_viewers=viewers,
                             client_timeout=5.0, on_pages=pages)
    srv.test_pages = pages
    srv.start()
    yield srv, live, viewers
    srv.stop()


def get(srv, path, method='GET'):
    conn = http.client.HTTPConnection(*srv.address, timeout=TIMEOUT)
    conn.request(method, path)
    r = conn.getresponse()
    body = r.read()
    conn.close()
    return r, body


def test_page_is_self_contained(served):
    srv, _, _ = served
    r, body = get(srv, '/')
    assert r.status == 200 and r.getheader('Content-Type').startswith('text/html')
    page = body.decode()
    assert 'src="/stream/left.mjpg"' in page and 'src="/stream/right.mjpg"' in page
    assert not re.search(r'(src|href)="(https?:)?//', page)      # no CDN, no external resource
    r, js = get(srv, '/app.js')
    assert r.status == 200 and b'EventSource' in js and b'http' not in js
    assert "default-src 'self'" in r.getheader('Content-Security-Policy')


@pytest.mark.parametrize('host, status', [
    ('127.0.0.1:8090', 200), ('localhost', 200), ('[::1]:8090', 200), ('LOCALHOST:1', 200),
    ('evil.example:8090', 403), ('127.0.0.1.evil.example', 403), ('[::2]', 403)])
def test_host_header_guards_against_dns_rebinding(served, host, status):
    srv, _, _ = served
    conn = http.client.HTTPConnection(*srv.address, timeout=TIMEOUT)
    conn.putrequest('GET', '/state.json', skip_host=True)
    conn.putheader('Host', host)
    conn.endheaders()
    assert conn.getresponse().status == status
    conn.close()


def test_state_json(served):
    srv, live, _ = served
    live.set_distances([0.001, 0.01, 0.05, float('nan')], srv.clock())
    r, body = get(srv, '/state.json')
    assert r.status == 200
    state = json.loads(body)
    assert [t['colour'] for t in state['tools']] == ['#ff0000', '#ffff00', '#00ff00', '#a0a0a0']


@pytest.mark.parametrize('method', ['POST', 'PUT', 'DELETE', 'PATCH', 'OPTIONS'])
def test_read_only(served, method):
    srv, _, _ = served
    r, _ = get(srv, '/state.json', method)
    assert r.status == 405 and r.getheader('Allow') == 'GET, HEAD'


def test_bad_requests_are_answered_and_counted(served):
    srv, _, _ = served
    assert get(srv, '/nothing')[0].status == 404
    assert get(srv, '/frame/left.jpg')[0].status == 404          # no frame yet
    for raw, code in ((b'GARBAGE\r\n\r\n', b'400'), (b'GET / HTTP/9.9\r\n\r\n', b'505'),
                      (b'\x00\xff' * 100 + b'\r\n\r\n', b'400'), (b'GET /' + b'a' * 70000 + b' HTTP/1.1\r\n\r\n', b'414')):
        with socket.create_connection(srv.address, timeout=TIMEOUT) as s:
            s.sendall(raw)
            answer = b''.join(iter(lambda: s.recv(4096), b''))
            assert code in answer[:300], (raw[:20], answer[:300])
    with socket.create_connection(srv.address, timeout=TIMEOUT) as s:
        s.sendall(b'GET / HT')                                        # closed half-way
    assert srv.counters.copy()['bad requests'] >= 6
    assert get(srv, '/')[0].status == 200                             # still serving


def read_part(resp):
    """One multipart part: (headers, jpeg bytes)."""
    headers = {}
    while True:
        line = resp.fp.readline().strip()
        if not line:
            if headers:
                break
            continue
        if line == b'--' + BOUNDARY:
            continue
        k, v = line.decode().split(':', 1)
        headers[k.strip().lower()] = v.strip()
    data = resp.fp.read(int(headers['content-length']))
    return headers, data


def test_mjpeg_forwards_the_received_bytes_and_subscribes_lazily(served):
    srv, live, viewers = served
    assert viewers.calls == []                       # nothing subscribed before a browser
    conn = http.client.HTTPConnection(*srv.address, timeout=TIMEOUT)
    conn.request('GET', '/stream/left.mjpg')
    resp = conn.getresponse()
    assert resp.status == 200
    assert resp.getheader('Content-Type') == 'multipart/x-mixed-replace; boundary=' + BOUNDARY.decode()
    assert viewers.wait([1])
    frames = [b'\xff\xd8\xff\xe0frame-%d\xff\xd9' % i for i in range(3)]
    for f in frames:
        live.frames['left'].put(f, 1.0)
        headers, data = read_part(resp)
        assert headers['content-type'] == 'image/jpeg' and data == f
    r, body = get(srv, '/frame/left.jpg')
    assert r.status == 200 and body == frames[-1]
    resp.close()
    conn.close()
    assert viewers.wait([1, 0])                      # unsubscribed when the last viewer left


def test_events_push_the_payload(served):
    srv, live, viewers = served
    assert srv.test_pages.calls == []                # energies not subscribed before a page
    conn = http.client.HTTPConnection(*srv.address, timeout=TIMEOUT)
    conn.request('GET', '/events')
    resp = conn.getresponse()
    assert resp.getheader('Content-Type') == 'text/event-stream'
    assert srv.test_pages.wait([1]) and viewers.calls == []
    seen = []
    deadline = time.monotonic() + TIMEOUT
    while len(seen) < 2 and time.monotonic() < deadline:
        live.set_distances([0.001 * (len(seen) + 1)] * 4, srv.clock())
        line = resp.fp.readline()
        if line.startswith(b'data: '):
            d = json.loads(line[6:])['tools'][0]['distance_mm']
            if not seen or d != seen[-1]:
                seen.append(d)
    resp.close()
    conn.close()
    assert len(seen) == 2
    assert srv.test_pages.wait([1, 0])               # unsubscribed when the last page left


def test_long_lived_connections_are_limited(served):
    srv, _, viewers = served
    conns = []
    for _ in range(3):
        c = http.client.HTTPConnection(*srv.address, timeout=TIMEOUT)
        c.request('GET', '/events')
        r = c.getresponse()
        assert r.status == 200
        conns.append((c, r))      # the response must stay referenced: its socket is the stream
    assert get(srv, '/stream/right.mjpg')[0].status == 503
    assert srv.counters.copy()['refused (too many clients)'] == 1
    assert get(srv, '/state.json')[0].status == 200       # short requests still served
    for c, r in conns:
        r.close()
        c.close()
    deadline = time.monotonic() + TIMEOUT
    while srv.clients()[0] and time.monotonic() < deadline:
        time.sleep(0.05)
    assert srv.clients() == (0, 0)
    assert viewers.calls == []


def test_stop_releases_open_streams():
    live = LiveState(THR, COL, ['t'], 2.0)
    srv = OperatorViewServer(live, '127.0.0.1', 0)
    srv.start()
    conn = http.client.HTTPConnection(*srv.address, timeout=TIMEOUT)
    conn.request('GET', '/stream/left.mjpg')
    resp = conn.getresponse()
    t0 = time.monotonic()
    srv.stop()
    resp.read()                                          # the stream ends
    assert time.monotonic() - t0 < TIMEOUT


def test_ipv6_loopback():
    live = LiveState(THR, COL, ['t'], 2.0)
    try:
        srv = OperatorViewServer(live, '::1', 0)
    except OSError:
        pytest.skip('no IPv6 loopback on this host')
    srv.start()
    try:
        conn = http.client.HTTPConnection('::1', srv.address[1], timeout=TIMEOUT)
        conn.request('GET', '/state.json')
        assert conn.getresponse().status == 200
        conn.close()
    finally:
        srv.stop()
