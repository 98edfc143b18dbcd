"""Small helpers of the saras_drivers benchmarks (bench/*.py): a free TCP port for a private
roscore and the CPU time of a process. Linux /proc only."""
import os
import socket


def free_port():
    """A TCP port on 127.0.0.1 that was free when asked."""
    s = socket.socket()
    s.bind(('127.0.0.1', 0))
    port = s.getsockname()[1]
    s.close()
    return port


def cpu_seconds(pid):
    """User + system CPU time [s] of process ``pid``, or None when it is gone."""
    try:
        with open('/proc/%d/stat' % pid) as f:
            fields = f.read().rsplit(')', 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')
