"""saras_bringup.supervisor: the recorder's children (bag_recorder and the in-process part's loader)
run and stop as one unit; stand-in children are shell commands (no ROS)."""
import os
import signal
import threading
import time

import pytest

from saras_bringup import supervisor
from saras_bringup.supervisor import Children, exit_status, start_part

TRAPPED = 'trap "exit 0" INT TERM; while :; do sleep 0.05; done'   # closes its "bag" on a signal: exit 0
FOREVER = 'while :; do sleep 0.05; done'                            # default signal disposition


class Log(list):
    def __call__(self, text):
        self.append(text)


@pytest.fixture
def handlers():
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    yield
    for s, h in saved.items():
        signal.signal(s, h)


def sh(script):
    return ['/bin/sh', '-c', script]


def stop_all(children):
    children.signal_all(signal.SIGKILL)
    for _, p in children.procs:
        p.wait()


def wait(children, limit=10.0):
    """children.wait(), with every child killed (SIGKILL: a failed assertion, not a hang) after ``limit`` s."""
    guard = threading.Timer(limit, lambda: [p.kill() for _, p in children.procs if p.poll() is None])
    guard.start()
    try:
        return children.wait()
    finally:
        guard.cancel()


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_a_signal_reaches_both_children_and_both_exit_0(handlers, signum):
    log = Log()
    children = Children(log)
    children.install()
    children.start('part', sh(TRAPPED), essential=False)
    children.start('main', sh(TRAPPED))
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signum))
    timer.start()
    t0 = time.monotonic()
    try:
        results = wait(children)
    finally:
        timer.cancel()
        stop_all(children)
    assert results == [('part', 0), ('main', 0)]
    assert time.monotonic() - t0 < 5.0
    assert exit_status(results, log) == 0 and log == []


def test_a_child_can_get_another_signal_than_the_one_received(handlers):
    children = Children()
    children.install()
    only_int = sh('trap "exit 0" INT; ' + FOREVER)                     # dies on SIGTERM
    children.start('loader', only_int, essential=False, translate={signal.SIGTERM: signal.SIGINT})
    children.start('plain', only_int)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGTERM))
    timer.start()
    try:
        results = wait(children)
    finally:
        timer.cancel()
        stop_all(children)
    assert results == [('loader', 0), ('plain', -signal.SIGTERM)]


def test_an_essential_child_ending_stops_the_other_and_fails_the_recording():
    log = Log()
    children = Children(log)
    children.start('the part', sh(FOREVER), essential=False)
    children.start('bag_recorder', sh('sleep 0.3; exit 3'))
    t0 = time.monotonic()
    try:
        results = wait(children)
    finally:
        stop_all(children)
    assert results == [('the part', -signal.SIGINT), ('bag_recorder', 3)]
    assert time.monotonic() - t0 < 5.0
    assert exit_status(results, log) == 1
    assert 'bag_recorder ended (exit 3): stopping the part' in log
    assert 'bag_recorder failed (exit 3)' in log and 'the part failed (killed by signal 2)' in log


def test_the_part_ending_alone_leaves_the_main_recording_running(handlers):
    log = Log()
    children = Children(log)
    children.install()
    children.start('the part', sh('exit 4'), essential=False)
    main = children.start('bag_recorder', sh(TRAPPED))
    timer = threading.Timer(1.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        t0 = time.monotonic()
        results = wait(children)
    finally:
        timer.cancel()
        stop_all(children)
    assert time.monotonic() - t0 > 1.0            # bag_recorder ran on until the SIGINT
    assert main.returncode == 0 and results == [('the part', 4), ('bag_recorder', 0)]
    assert any('the part ended (exit 4); the rest of the recording goes on' in line for line in log)
    assert exit_status(results, log) == 1 and log[-1] == 'the part failed (exit 4)'


def test_children_get_sigint_even_when_it_is_ignored_here(handlers):
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # as in a background job of a shell script
    children = Children()
    proc = children.start('child', sh('exec sleep 30'))
    try:
        time.sleep(0.2)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(5) == -signal.SIGINT
    finally:
        stop_all(children)


def test_start_part_without_its_manager_starts_nothing(tmp_path, monkeypatch):
    monkeypatch.setattr(supervisor, 'POLL', 0.05)
    log, children = Log(), Children()
    t0 = time.monotonic()
    assert not start_part(children, 'part', sh(FOREVER), str(tmp_path / 'p.bag'), lambda: False, log, 0.3)
    assert 0.3 <= time.monotonic() - t0 < 2.0
    assert children.procs == [] and 'did not appear within 0 s' in log[0]


def test_start_part_whose_loader_fails_is_a_fallback(tmp_path, monkeypatch):
    monkeypatch.setattr(supervisor, 'POLL', 0.05)
    log, children = Log(), Children()
    assert not start_part(children, 'part', sh('exit 255'), str(tmp_path / 'p.bag'), lambda: True, log, 1.0, 5.0)
    assert children.procs == [] and log == ['ERROR: part ended (exit 255) before opening %s.active'
                                            % (tmp_path / 'p.bag')]


def test_start_part_waits_for_the_manager_then_for_the_open_part_bag(tmp_path, monkeypatch):
    monkeypatch.setattr(supervisor, 'POLL', 0.05)
    log, children = Log(), Children()
    part = str(tmp_path / 'p.teleop.bag')
    asked = []
    manager_up = lambda: asked.append(1) or len(asked) > 3          # noqa: E731: appears at the 4th check
    loader = sh('sleep 0.5; touch "$0.active"; ' + FOREVER) + [part]
    try:
        assert start_part(children, 'part', loader, part, manager_up, log, 5.0, 5.0)
        assert len(asked) == 4 and os.path.exists(part + '.active')
        assert [n for n, _ in children.running()] == ['part'] and 'part' not in children.essential
        assert children.translate['part'] == {signal.SIGTERM: signal.SIGINT}
        # still running without opening its bag: the main recording starts anyway, with a warning
        assert start_part(children, 'slow', sh(FOREVER), str(tmp_path / 'q.bag'), lambda: True, log, 1.0, 0.3)
        assert 'has not opened' in log[-1]
    finally:
        stop_all(children)
    assert log[:-1] == []
