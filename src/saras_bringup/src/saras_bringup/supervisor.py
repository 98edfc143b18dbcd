"""Child processes that end as one unit: the recorder's ``bag_recorder`` and the loader of its
in-process part (``saras_bringup/StreamRecorder`` nodelet), see ``scripts/recorder``.

:class:`Children` starts the children, forwards SIGINT/SIGTERM to every one still running (each
closes its bag; a child can get another signal than the one received: the part's loader unloads its
nodelet on SIGINT only), and waits for all of them. When an *essential* child exits on its own
(``bag_recorder``: a full disk, the master gone) the others get SIGINT: the recording is over. A
non-essential one (the part's loader, which ends when its nodelet manager dies) ends alone: the rest
of the recording goes on. :func:`exit_status` is 0 only when every child exited 0 and names the ones
that did not.
:func:`start_part` starts the part's loader once its nodelet manager exists and waits until the part
bag is open. No ROS needed: the manager check is passed in.
"""
import os
import signal
import subprocess
import time

POLL = 0.2   # [s] child and condition polling (the supervisor otherwise sleeps)


def _default_signals():
    # a background job of a non-interactive shell starts with SIGINT ignored, and a child keeps an
    # ignored signal across exec: the children get the default disposition (and install their own)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_DFL)


class Children(object):
    """Named child processes run and stopped together."""

    def __init__(self, log=None):
        self.procs = []            # [(name, Popen)] in start order
        self.essential = set()     # names whose end on its own stops the others
        self.translate = {}        # name: {received signal: signal sent to it}
        self.stopping = False      # a stop was requested (signal) or a child ended on its own
        self.log = log if log is not None else (lambda text: None)

    def start(self, name, argv, essential=True, translate=None, **popen_kwargs):
        """Start child ``name``; ``translate``: {signal received here: signal forwarded to it}."""
        proc = subprocess.Popen(argv, preexec_fn=_default_signals, **popen_kwargs)
        self.procs.append((name, proc))
        self.translate[name] = dict(translate or {})
        if essential:
            self.essential.add(name)
        if self.stopping:          # a signal arrived while it was starting
            proc.send_signal(signal.SIGINT)
        return proc

    def running(self):
        return [(name, p) for name, p in self.procs if p.poll() is None]

    def signal_all(self, signum):
        for name, proc in self.running():
            try:
                proc.send_signal(self.translate.get(name, {}).get(signum, signum))
            except OSError:        # exited in between
                pass

    def install(self, signals=(signal.SIGINT, signal.SIGTERM)):
        """Forward ``signals`` received by this process to every running child."""
        for signum in signals:
            signal.signal(signum, self._forward)

    def _forward(self, signum, _frame):
        self.stopping = True
        self.signal_all(signum)

    def wait_for(self, condition, timeout):
        """Poll ``condition()`` until it is true (True), or False at ``timeout`` [s], on a stop
        request, or when a child has exited."""
        deadline = time.monotonic() + timeout
        while not self.stopping and len(self.running()) == len(self.procs):
            if condition():
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(POLL)
        return False

    def wait(self):
        """Wait for every child; [(name, return code)]. An essential child that exits while no stop
        was requested stops the others (SIGINT); a non-essential one is only logged."""
        logged = set()
        while self.running():
            for name, proc in self.procs:
                if self.stopping or proc.poll() is None or name in logged:
                    continue
                logged.add(name)
                if name in self.essential:
                    self.log('%s ended (%s): stopping %s' % (name, describe(proc.returncode),
                                                           ', '.join(n for n, _ in self.running())))
                    self.stopping = True
                    self.signal_all(signal.SIGINT)
                else:
                    self.log('ERROR: %s ended (%s); the rest of the recording goes on'
                             % (name, describe(proc.returncode)))
            time.sleep(POLL)
        return [(name, p.returncode) for name, p in self.procs]


def describe(returncode):
    return ('killed by signal %d' % -returncode) if returncode < 0 else ('exit %d' % returncode)


def exit_status(results, log):
    """0 when every child of ``results`` ([(name, return code)]) exited 0, else 1 (each failure logged)."""
    failed = [(name, rc) for name, rc in results if rc != 0]
    for name, rc in failed:
        log('%s failed (%s)' % (name, describe(rc)))
    return 1 if failed else 0


def start_part(children, name, argv, part_bag, manager_exists, log, manager_timeout=10.0, open_timeout=20.0):
    """Start the part's loader ``argv`` as child ``name`` once ``manager_exists()``; True once
    ``part_bag``.active exists (or after ``open_timeout`` s with the loader still running: it may
    still open it). False, with the reason logged, when the manager did not appear within
    ``manager_timeout`` s, the loader exited first (the caller records the part's streams itself),
    or a stop was requested."""
    if not children.wait_for(manager_exists, manager_timeout):
        if not children.stopping:
            log('ERROR: %s: its nodelet manager did not appear within %.0f s' % (name, manager_timeout))
        return False
    # the loader unloads the nodelet (which closes the part bag) on SIGINT only; roscpp dies on SIGTERM
    children.start(name, argv, essential=False, translate={signal.SIGTERM: signal.SIGINT})
    if children.wait_for(lambda: os.path.exists(part_bag + '.active'), open_timeout):
        return True
    if children.stopping:
        return False
    proc = children.procs[-1][1]
    if proc.poll() is not None:
        log('ERROR: %s ended (%s) before opening %s.active' % (name, describe(proc.returncode), part_bag))
        children.procs.pop()
        return False
    log('WARNING: %s has not opened %s.active after %.0f s; recording the main bag anyway'
        % (name, part_bag, open_timeout))
    return True
