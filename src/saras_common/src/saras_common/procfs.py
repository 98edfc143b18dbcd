"""Processes as Linux ``/proc`` shows them: CPU time, parent, start time, command line, environment.
One reader for the platform's CPU accounting (``saras_bringup.proc_cpu``) and the benchmarks."""
import os

CLK_TCK = os.sysconf('SC_CLK_TCK')


def _read(path):
    try:
        with open(path, 'rb') as stream:
            return stream.read()
    except OSError:
        return None


def stat(pid):
    """(ppid, utime + stime [clock ticks], start time [ticks since boot]) of ``pid``, None when it is gone."""
    raw = _read('/proc/%d/stat' % pid)
    if raw is None:
        return None
    fields = raw[raw.rindex(b')') + 2:].split()   # after "pid (comm) "; comm may hold spaces and ')'
    return int(fields[1]), int(fields[11]) + int(fields[12]), int(fields[19])


def cpu_seconds(pid):
    """User + system CPU time [s] of ``pid``, None when it is gone."""
    st = stat(pid)
    return None if st is None else st[1] / CLK_TCK


def pids():
    """Every process id in /proc."""
    return [int(d) for d in os.listdir('/proc') if d.isdigit()]


def cmdline(pid):
    """argv of ``pid`` as bytes, [] when it is gone or has none (a kernel thread)."""
    raw = _read('/proc/%d/cmdline' % pid)
    return [a for a in raw.split(b'\0') if a] if raw else []


def environ(pid):
    """Environment of ``pid`` as {bytes: bytes}, {} when unreadable."""
    raw = _read('/proc/%d/environ' % pid) or b''
    return dict(e.split(b'=', 1) for e in raw.split(b'\0') if b'=' in e)


def comm(pid):
    """Short program name of ``pid`` ('?' when it is gone)."""
    raw = _read('/proc/%d/comm' % pid)
    return raw.decode(errors='replace').strip() if raw else '?'


def threads(pid):
    """{thread name: utime + stime [clock ticks]} of the live threads of ``pid``, summed per name
    (``/proc/PID/task/TID``); {} when it is gone."""
    try:
        tids = [int(t) for t in os.listdir('/proc/%d/task' % pid) if t.isdigit()]
    except OSError:
        return {}
    out = {}
    for tid in tids:
        raw = _read('/proc/%d/task/%d/stat' % (pid, tid))
        if raw is None:
            continue
        name = raw[raw.index(b'(') + 1:raw.rindex(b')')].decode(errors='replace')
        fields = raw[raw.rindex(b')') + 2:].split()
        out[name] = out.get(name, 0) + int(fields[11]) + int(fields[12])
    return out
