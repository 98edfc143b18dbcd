"""Clocks across the namespace deployment: chrony with the shipped configurations, and the clock
monitor over the LAN with a responder under libfaketime.

chrony: chronyd runs with -x (never touches the system clock) in core_pc with config/chrony/
core_pc.conf and in teleop_pc with client.conf; the client must select the core PC as its source
at stratum + 1. All namespaces share one kernel clock, so this proves the configurations and the
NTP path over the LAN, not a correction of a wrong clock. Only path directives (drift file, logs,
pid file, command socket) are replaced by run-directory ones, and the addresses by the test's.

clock monitor: monitor in core_pc, responder in teleop_pc under libfaketime (+50 ms): the offset
is measured over the bridge within 1 ms. Skips without root.
"""
import re
import subprocess
import time
from pathlib import Path

import pytest
from netns_helpers import Deployment

CHRONY_DIR = Path(__file__).resolve().parents[1] / 'config' / 'chrony'
SCRIPTS = Path(__file__).resolve().parents[1] / 'scripts'
FAKETIME_LIB = '/usr/lib/x86_64-linux-gnu/faketime/libfaketime.so.1'
CLUSTER = Deployment('sarasclk', '10.77.8', roles=['core_pc', 'teleop_pc'])
RUN_PATHS = ('driftfile', 'logdir', 'rtcsync', 'pidfile', 'bindcmdaddress', 'cmdport')


@pytest.fixture(scope='module')
def cluster():
    CLUSTER.up_or_skip()
    yield CLUSTER
    CLUSTER.down()


def run_config(shipped, name, replacements):
    """The shipped chrony file with run-directory paths and the test's addresses."""
    run = Path(CLUSTER.run_dir)
    lines = [line for line in shipped.read_text().splitlines()
             if line.split(' ', 1)[0] not in RUN_PATHS]
    text = '\n'.join(lines) + '\n'
    for pattern, value in replacements:
        text, count = re.subn(pattern, value, text, flags=re.M)
        assert count == 1, 'shipped %s: %r not found once' % (shipped.name, pattern)
    text += ('pidfile {r}/{n}.pid\nbindcmdaddress {r}/{n}.sock\ncmdport 0\n'
             'driftfile {r}/{n}.drift\n').format(r=run, n=name)
    path = run / (name + '.conf')
    path.write_text(text)
    return path


def chronyc(role, name, *args):
    sock = '%s/%s.sock' % (CLUSTER.run_dir, name)
    return CLUSTER.in_ns(role, 'chronyc', '-h', sock, '-n', *args).stdout


def test_chrony_client_follows_the_core_pc(cluster):
    core = cluster.addr['core_pc']
    server = run_config(CHRONY_DIR / 'core_pc.conf', 'core',
                        [(r'^allow 10\.77\.0\.0/24$', 'allow %s.0/24' % cluster.base)])
    client = run_config(CHRONY_DIR / 'client.conf', 'client',
                        [(r'^server core_pc ', 'server %s ' % core)])
    for role, conf, name in (('core_pc', server, 'core'), ('teleop_pc', client, 'client')):
        r = cluster.in_ns(role, 'chronyd', '-x', '-u', 'root', '-f', str(conf),
                          '-l', '%s/%s.log' % (cluster.run_dir, name))
        assert r.returncode == 0, r.stdout
    deadline = time.monotonic() + 40
    sources = ''
    while time.monotonic() < deadline and not re.search(r'^\^\* %s ' % re.escape(core),
                                                        sources, re.M):
        time.sleep(1)
        sources = chronyc('teleop_pc', 'client', 'sources')
    assert re.search(r'^\^\* %s ' % re.escape(core), sources, re.M), sources
    tracking = chronyc('teleop_pc', 'client', 'tracking')
    assert '(%s)' % core in tracking and re.search(r'^Stratum\s*: 9$', tracking, re.M), tracking
    log = Path(cluster.run_dir, 'client.log').read_text()
    assert 'Disabled control of system clock' in log


def test_clock_monitor_over_the_lan(cluster):
    master = cluster.popen('core_pc', 'roscore', '-p', '11311', stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    assert cluster.wait_master('teleop_pc')
    log = open(Path(cluster.run_dir, 'clock_monitor.log'), 'w')
    monitor = cluster.popen('core_pc', '/usr/bin/python3', str(SCRIPTS / 'clock_monitor'),
                            '_machines:=[teleop_pc]', '_period_s:=0.5',
                            stdout=log, stderr=subprocess.STDOUT)
    responder = cluster.popen('teleop_pc', 'env', 'LD_PRELOAD=' + FAKETIME_LIB,
                              'FAKETIME=+0.05', '/usr/bin/python3',
                              str(SCRIPTS / 'clock_responder'), '_machine:=teleop_pc',
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        offset, level, samples = None, None, 0
        deadline = time.monotonic() + 60
        while samples < 16 and time.monotonic() < deadline:
            out = cluster.in_ns('core_pc', 'timeout', '5', 'rostopic', 'echo', '-n', '1',
                                '/diagnostics').stdout
            m = re.search(r'level: (\d)\s+name: "clock_monitor: teleop_pc".*?'
                          r'key: "offset_ms"\s+value: "([-\d.na]+)".*?'
                          r'key: "samples"\s+value: "(\d+)"', out, re.S)
            if m:
                level, offset, samples = int(m.group(1)), float(m.group(2)), int(m.group(3))
        assert samples >= 16, (out, Path(cluster.run_dir, 'clock_monitor.log').read_text())
        print('teleop_pc under FAKETIME=+0.05: offset %.3f ms over the bridge' % offset)
        assert abs(offset - 50.0) <= 1.0, 'offset %.3f ms measured, 50 ms set' % offset
        assert level == 1  # WARN: above 2 ms
    finally:
        for process in (responder, monitor, master):
            process.terminate()
        log.close()
        cluster.down()  # ends what terminate() did not
