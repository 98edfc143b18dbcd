"""MasterWatch: loss of the ROS master is detected (refused, unreachable for grace s, or restarted)."""
import pytest

from saras_drivers.master_watch import MasterWatch


class Clock(object):
    t = 0.0

    def __call__(self):
        return self.t


def test_unreachable_for_grace_is_lost_once():
    clock, state, lost = Clock(), {'pid': 100, 'up': True}, []

    def probe():
        if not state['up']:
            raise TimeoutError('timed out')
        return state['pid']

    w = MasterWatch(probe, lost.append, grace=1.0, clock=clock)
    assert w.poll() is None
    state['up'] = False
    clock.t = 0.5
    assert w.poll() is None              # a short outage (timeouts: a loaded host) is tolerated
    clock.t = 1.0
    assert w.poll() is None
    clock.t = 1.6
    assert 'unreachable for 1.1 s' in w.poll()
    clock.t = 2.0
    w.poll()
    assert len(lost) == 1


def test_refused_connection_is_lost_at_once():
    # nothing listens on the master's port any more: the master died, no grace
    clock, state, lost = Clock(), {'up': True}, []

    def probe():
        if not state['up']:
            raise ConnectionRefusedError(111, 'Connection refused')
        return 100

    w = MasterWatch(probe, lost.append, grace=1.0, clock=clock)
    assert w.poll() is None
    state['up'] = False
    clock.t = 0.2
    assert 'ROS master gone' in w.poll()
    assert len(lost) == 1


def test_restarted_master_is_lost_at_once():
    clock, state, lost = Clock(), {'pid': 100}, []
    w = MasterWatch(lambda: state['pid'], lost.append, clock=clock)
    assert w.poll() is None
    state['pid'] = 200
    assert 'restarted (pid 100 -> 200)' in w.poll()
    assert len(lost) == 1


def test_outage_shorter_than_grace_then_back_is_fine():
    clock, state, lost = Clock(), {'up': True}, []

    def probe():
        if not state['up']:
            raise OSError('x')
        return 7

    w = MasterWatch(probe, lost.append, grace=1.0, clock=clock)
    w.poll()
    state['up'] = False
    clock.t = 0.8
    w.poll()
    state['up'] = True
    clock.t = 1.5
    assert w.poll() is None
    state['up'] = False
    clock.t = 2.0
    assert w.poll() is None              # the grace restarts
    assert lost == []


def test_bad_arguments():
    with pytest.raises(ValueError):
        MasterWatch(lambda: 1, print, period=0.0)
