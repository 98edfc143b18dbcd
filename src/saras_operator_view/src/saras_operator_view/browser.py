"""Headless Chromium driven over its DevTools protocol (ROS-free): load a page, evaluate
JavaScript, take a screenshot. Used by the operator view's rostest and the demo report.

    with HeadlessChromium('http://127.0.0.1:8090/') as browser:
        browser.wait_for("document.getElementById('eye-left').naturalWidth > 0", 30)
        browser.screenshot('page.png')
"""
import base64
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request

import websocket

#: Flags of a quiet, throw-away browser: no sandbox (containers), no GPU, no network besides the page.
FLAGS = ('--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync',
         '--disable-extensions', '--mute-audio', '--hide-scrollbars', '--remote-allow-origins=*')


class BrowserError(RuntimeError):
    """Chromium could not be started or driven."""


def find_chromium():
    for name in ('chromium', 'chromium-browser', 'google-chrome'):
        path = shutil.which(name)
        if path:
            return path
    raise BrowserError('no chromium binary on PATH (Debian package "chromium")')


class HeadlessChromium(object):
    def __init__(self, url, width=1400, height=900, timeout=60.0, binary=None, log=None):
        self._dir = tempfile.mkdtemp(prefix='saras-chromium-')
        self._log = open(log or os.devnull, 'wb')
        self._id = 0
        self.ws = None
        args = [binary or find_chromium()] + list(FLAGS) + [
            '--user-data-dir=' + self._dir, '--remote-debugging-port=0', '--window-size=%d,%d' % (width, height), url]
        self.proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=self._log, stderr=self._log)
        try:
            self._connect(timeout)
        except Exception:
            self.close()
            raise

    def _connect(self, timeout):
        deadline = time.monotonic() + timeout
        port_file = os.path.join(self._dir, 'DevToolsActivePort')
        page = None
        while page is None:
            if self.proc.poll() is not None:
                raise BrowserError('chromium exited with status %s' % self.proc.returncode)
            if time.monotonic() > deadline:
                raise BrowserError('chromium DevTools not reachable within %.0f s' % timeout)
            time.sleep(0.2)
            try:
                with open(port_file) as f:
                    port = int(f.readline())
                with urllib.request.urlopen('http://127.0.0.1:%d/json/list' % port, timeout=5) as r:
                    targets = json.load(r)
            except (OSError, ValueError):
                continue
            page = next((t for t in targets if t.get('type') == 'page'), None)
        self.ws = websocket.create_connection(page['webSocketDebuggerUrl'], timeout=timeout, suppress_origin=True)

    def call(self, method, **params):
        """Result of one DevTools command (events in between are skipped)."""
        self._id += 1
        self.ws.send(json.dumps({'id': self._id, 'method': method, 'params': params}))
        while True:
            reply = json.loads(self.ws.recv())
            if reply.get('id') == self._id:
                if 'error' in reply:
                    raise BrowserError('%s: %s' % (method, reply['error']))
                return reply.get('result', {})

    def evaluate(self, expression):
        """Value of a JavaScript expression in the page (JSON-serialisable)."""
        result = self.call('Runtime.evaluate', expression=expression, returnByValue=True)
        if 'exceptionDetails' in result:
            raise BrowserError('%s: %s' % (expression, result['exceptionDetails'].get('text')))
        return result.get('result', {}).get('value')

    def wait_for(self, expression, timeout, period=0.25):
        """Poll ``expression`` until truthy; its value, or the last (falsy) value after ``timeout`` [s]."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                value = self.evaluate(expression)
            except BrowserError:
                value = None
            if value or time.monotonic() > deadline:
                return value
            time.sleep(period)

    def screenshot(self, path):
        """PNG of the viewport to ``path``."""
        data = self.call('Page.captureScreenshot', format='png')['data']
        with open(path, 'wb') as f:
            f.write(base64.b64decode(data))

    def close(self):
        if self.ws is not None:
            try:
                self.ws.close()
            except Exception:  # the browser may be gone already
                pass
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


#: JavaScript: the page state the tests and the demo check.
PAGE_STATE = """(() => {
  const img = e => document.getElementById('eye-' + e);
  const dist = [...document.querySelectorAll('#tools td[data-tool]')];
  return {width_left: img('left').naturalWidth, width_right: img('right').naturalWidth,
          frames_left: +document.getElementById('frames-left').textContent,
          frames_right: +document.getElementById('frames-right').textContent,
          link: document.getElementById('link').textContent,
          distances: dist.map(td => td.textContent), regions: dist.map(td => td.dataset.region),
          tanks: [...document.querySelectorAll('#tanks tr')].map(tr => tr.textContent),
          health: [...document.querySelectorAll('#health tr')].map(tr => tr.textContent)};
})()"""
