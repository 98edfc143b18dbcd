"""SourceWatch: the set-point publisher's disappearance is reported once per loss."""
import pytest

from saras_drivers.source_watch import SourceWatch


def test_loss_is_reported_once_when_the_count_falls_to_zero():
    state, lost = {'n': 0}, []
    w = SourceWatch(lambda: state['n'], lambda: lost.append(1))
    assert not w.poll()                  # never connected yet: nothing lost
    state['n'] = 2
    assert not w.poll()
    state['n'] = 1                       # one of two publishers left: the source is still there
    assert not w.poll()
    state['n'] = 0
    assert w.poll() and lost == [1]
    assert not w.poll() and lost == [1]  # once per loss
    state['n'] = 1
    assert not w.poll()
    state['n'] = 0
    assert w.poll() and lost == [1, 1] and w.losses == 2


def test_bad_period():
    with pytest.raises(ValueError):
        SourceWatch(lambda: 0, print, period=0.0)
