"""DipServo + ScriptedMotion: the scripted dip presses the tool a few mm into the tissue wherever the
incremental teleoperation left the tool (engage phase, lost motion), and leaves it again."""
import collections

import pytest

from saras_simulation.dip_servo import DipServo
from saras_simulation.touchball_console import ScriptedMotion

TISSUE_Z = 0.07      # [m] flat tissue
SCALE = 0.5          # master -> slave


def run(engage, slave_start, servo=True, duration=50.0, dt=0.004, delay=0.12, obs_period=1.0 / 30):
    """Teleoperation stand-in: the tip follows SCALE x the handle's motion since ``engage`` [s],
    ``delay`` [s] late; the servo sees the tip every ``obs_period`` [s]. Returns [(t, tip, b)]."""
    s = DipServo(depth=0.003, site=(0.0, 0.012), max_offset=0.2) if servo else None
    m = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.2, dip_period=20.0, dip_duration=9.0,
                       dip_start=5.0, servo=s)
    hist, out, anchor, next_obs = collections.deque(), [], None, 0.0
    t = 0.0
    while t < duration:
        hist.append((t, m(t).position))
        if t >= engage and anchor is None:
            anchor = hist[-1][1]
        while len(hist) > 1 and hist[1][0] <= t - delay:
            hist.popleft()                                    # hist[0]: the handle `delay` ago
        tip = tuple(slave_start)
        if anchor is not None and t - delay >= engage:
            tip = tuple(s0 + SCALE * (p - a) for s0, p, a in zip(slave_start, hist[0][1], anchor))
        if s is not None and t >= next_obs:                   # the arm's pose flows before the teleoperation engages
            s.observe(t, tip, tip[2] - TISSUE_Z)
            next_obs = t + obs_period
        if anchor is not None:
            out.append((t, tip, m.dip_weight(t)))
        t += dt
    return out


@pytest.mark.parametrize('engage,start', [(0.0, (0.005, 0.032, 0.124)), (3.1, (0.005, 0.032, 0.124)),
                                          (17.0, (0.0, 0.02, 0.14)), (2.0, (0.01, 0.04, 0.10)),
                                          (9.0, (0.0, 0.03, 0.13))])  # engaged in the middle of a dip
def test_servoed_dip_presses_2_to_5_mm_wherever_the_tool_starts(engage, start):
    out = run(engage, start)
    held = [tip for (t, tip, b) in out if b >= 1.0 and (t - 5.0) % 20.0 > 4.0 and t > engage + 20.0]
    assert held, 'no hold phase'
    depths = [TISSUE_Z - tip[2] for tip in held]
    assert 0.002 <= min(depths) and max(depths) <= 0.005, (min(depths), max(depths))
    deepest = max(TISSUE_Z - tip[2] for (_, tip, _) in out)
    assert deepest < 0.008                                    # no overshoot into the tissue
    assert abs(held[-1][1] - 0.012) < 0.004                   # aimed at the site


def test_tool_leaves_the_tissue_between_dips():
    out = run(0.0, (0.005, 0.032, 0.124))
    free = [tip for (t, tip, b) in out if 16.0 < t < 24.0]   # between the first and the second dip
    assert min(tip[2] for tip in free) > TISSUE_Z + 0.01


def test_without_observations_the_dip_is_open_loop():
    m = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12, servo=DipServo())
    ref = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12)
    for t in (4.0, 6.0, 9.0, 12.0):
        assert m(t).position == pytest.approx(ref(t).position)


def test_stale_observation_holds_the_offsets():
    s = DipServo(depth=0.003, timeout=0.5)
    s.observe(0.0, (0.0, 0.0, 0.1), 0.03)
    s.update(0.0, 1.0)
    s.update(0.02, 1.0)
    held = s.update(0.04, 1.0)
    assert held[2] < 0.0                                      # moving down
    assert s.update(5.0, 1.0) == pytest.approx(s.update(5.04, 1.0))   # stale: held
    assert s.update(5.1, 0.0) is None or s.offset == 0.0      # dip over: released


@pytest.mark.parametrize('kw', [{'depth': -0.001}, {'speed': float('nan')}, {'site': (0.0,)}])
def test_bad_parameters_are_rejected(kw):
    with pytest.raises(ValueError):
        DipServo(**kw)


def test_a_dip_begun_blind_stays_open_loop_without_a_jump():
    s = DipServo()
    m = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12, servo=s)
    ref = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12)
    m(6.0)
    s.observe(6.5, (0.0, 0.0, 0.1), 0.03)
    assert m(7.0).position == pytest.approx(ref(7.0).position)      # same dip: still open loop
    m(15.0)                                                          # between dips
    s.observe(25.0, (0.0, 0.0, 0.1), 0.03)
    assert m(27.0).position != pytest.approx(ref(27.0).position)    # next dip: servoed
