"""Poller: the watches' polling thread stops on stop(), or on the first event when it is final."""
import pytest

from saras_drivers.poller import Poller


class Counting(Poller):
    def __init__(self, once, events_from=0):
        Poller.__init__(self, 0.002, 'counting', once)
        self.calls, self.events_from = 0, events_from

    def poll(self):
        self.calls += 1
        return self.calls > self.events_from


def test_a_final_event_ends_the_thread():
    p = Counting(once=True, events_from=2)
    t = p.start()
    t.join(5.0)
    assert not t.is_alive() and p.calls == 3


def test_a_repeatable_event_keeps_polling_until_stop():
    p = Counting(once=False)
    t = p.start()
    while p.calls < 5 and t.is_alive():
        t.join(0.01)
    assert t.is_alive() and p.calls >= 5
    p.stop()
    t.join(5.0)
    assert not t.is_alive()


def test_bad_period():
    with pytest.raises(ValueError):
        Poller(0.0, 'x', True)
