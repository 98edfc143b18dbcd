"""Small helpers of the saras_simulation benchmarks (bench/*.py) and tests: a free TCP port for a
private roscore, the CPU time and command lines of processes (from ``saras_common.procfs``), a built
executable of this package and the clean stop of the process groups a benchmark started."""
import os
import signal
import socket
import subprocess
import time

from saras_common import procfs
from saras_common.procfs import cpu_seconds  # noqa: F401 (the benchmarks' CPU time of a process)


def free_port():
    """A TCP port on 127.0.0.1 that was free when asked."""
    s = socket.socket()
    s.bind(('127.0.0.1', 0))
    port = s.getsockname()[1]
    s.close()
    return port


def find_devel_executable(name, package='saras_simulation'):
    """Path of the built executable ``lib/<package>/<name>`` in ``$DEVEL_DIR`` or, after it, the
    prefixes of ``$CMAKE_PREFIX_PATH`` (a sourced devel or install space); None when not built."""
    prefixes = [p for p in os.environ.get('CMAKE_PREFIX_PATH', '').split(':') if p]
    if os.environ.get('DEVEL_DIR'):
        prefixes.insert(0, os.environ['DEVEL_DIR'])
    for p in prefixes:
        exe = os.path.join(p, 'lib', package, name)
        if os.access(exe, os.X_OK):
            return exe
    return None


def stop_process_groups(procs, timeout=10.0):
    """SIGINT the process group of every ``subprocess.Popen`` in ``procs`` (started with
    ``start_new_session=True``), newest first, as roslaunch expects; SIGKILL the groups that are
    still alive ``timeout`` seconds later."""
    for p in reversed(procs):
        try:
            os.killpg(p.pid, signal.SIGINT)
        except OSError:
            pass
    for p in reversed(procs):
        try:
            p.wait(timeout)
        except subprocess.TimeoutExpired:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except OSError:
                pass


def process_cmdlines():
    """(pid, [argv bytes]) of every process readable in /proc."""
    for pid in procfs.pids():
        args = procfs.cmdline(pid)
        if args:
            yield pid, args


def best_us(fn, n, repeat):
    """Smallest CPU time [us] per item over ``repeat`` runs of ``fn`` (which handles ``n`` items)."""
    best = float('inf')
    for _ in range(repeat):
        t = time.process_time()
        fn()
        best = min(best, (time.process_time() - t) / n * 1e6)
    return best
