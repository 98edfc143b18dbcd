import pytest

from saras_simulation.operator_reaction import HoldReaction, ReactiveSource
from saras_simulation.touchball_console import Intention


def test_one_press_after_the_reaction_time_then_a_pause():
    r = HoldReaction(reaction_time=0.5, press_time=0.3, min_interval=1.0)
    assert r.on_hold(10.0)
    assert not r.on_hold(10.1)                  # already reacting
    assert not r.pressed(10.4)
    assert r.pressed(10.5) and r.pressed(10.79)
    assert not r.pressed(10.81)                 # released
    assert not r.on_hold(11.5)                  # min_interval after the release
    assert r.on_hold(11.9) and r.reactions == 2


def test_no_hold_no_press():
    r = HoldReaction()
    assert not any(r.pressed(t * 0.1) for t in range(100))


def test_bad_times_are_refused():
    with pytest.raises(ValueError):
        HoldReaction(reaction_time=-1.0)


def test_reactive_source_presses_the_clutch_of_the_wrapped_motion():
    now = [0.0]
    r = HoldReaction(reaction_time=0.2, press_time=0.3, min_interval=0.0)
    base = lambda t: Intention((1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0), 0.4, False, False)
    src = ReactiveSource(base, r, lambda: now[0])
    assert not src(0.0).clutch
    r.on_hold(0.0)
    now[0] = 0.25
    it = src(0.25)
    assert it.clutch and it.position == (1.0, 2.0, 3.0) and it.clip_raw == 0.4
    now[0] = 0.6
    assert not src(0.6).clutch
