"""saras_common.procfs: a process's CPU time, parent, command line and environment from /proc."""
import os
import subprocess
import sys
import time

from saras_common import procfs


def test_a_busy_child_as_proc_shows_it():
    code = 'import time\nt = time.process_time()\nwhile time.process_time() - t < 0.3: pass\ntime.sleep(30)'
    child = subprocess.Popen([sys.executable, '-c', code, '__name:=probe'], env=dict(os.environ, PROBE_VAR='42'))
    try:
        deadline = time.monotonic() + 20
        while (procfs.cpu_seconds(child.pid) or 0.0) < 0.25 and time.monotonic() < deadline:
            time.sleep(0.05)
        ppid, ticks, start = procfs.stat(child.pid)
        assert ppid == os.getpid() and start > 0
        assert ticks / procfs.CLK_TCK >= 0.25
        assert b'__name:=probe' in procfs.cmdline(child.pid)
        assert procfs.environ(child.pid)[b'PROBE_VAR'] == b'42'
        assert child.pid in procfs.pids()
        assert procfs.comm(child.pid).startswith('python')
    finally:
        child.kill()
        child.wait()


def test_a_gone_process_reads_as_none():
    child = subprocess.Popen(['true'])
    child.wait()
    assert procfs.stat(child.pid) is None and procfs.cpu_seconds(child.pid) is None
    assert procfs.cmdline(child.pid) == [] and procfs.environ(child.pid) == {} and procfs.comm(child.pid) == '?'
