"""DipServo + ScriptedMotion: the scripted surgeon works near the tissue and every dip presses the
tool a few mm into it wherever the incremental teleoperation left the tool (engage phase, lost
motion), through a teleoperation stand-in with the set-point lead limit and the arm lag of a loaded
host, without saturating the lead long enough for an "arm not following" hold."""
import collections

import pytest

from saras_simulation.dip_servo import DipServo
from saras_simulation.touchball_console import ScriptedMotion

TISSUE_Z = 0.07      # [m] flat tissue
SCALE = 0.5          # master -> slave


def test_without_observations_the_surgeon_does_not_dip():
    m = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12, servo=DipServo())
    path = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12, dip_period=0.0)
    blind = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12)
    for t in (4.0, 6.0, 9.0, 12.0):
        assert m(t).position == pytest.approx(path(t).position)
    assert blind(9.0).position[2] < path(9.0).position[2] - 0.05    # what a blind dip would do


def test_stale_observation_holds_the_offsets():
    s = DipServo(depth=0.003, timeout=0.5)
    s.observe(0.0, (0.0, 0.0, 0.1), 0.03)
    s.update(0.0, 1.0)
    s.update(0.02, 1.0)
    held = s.update(0.04, 1.0)
    assert held[2] < 0.0                                      # moving down
    assert s.update(5.0, 1.0) == pytest.approx(s.update(5.04, 1.0))   # stale: held
    assert s.update(5.1, 0.0) == pytest.approx(held)         # dip over, still stale: the offsets stay


def test_between_dips_the_tip_is_brought_to_the_working_height():
    s = DipServo(hover=0.012, speed=0.012, gain=2.0, slack=0.006, scale=0.5)
    tip = [0.0, 0.0, 0.12]
    for i in range(50):                                       # 5 cm above, following: down at `speed`
        s.observe(0.04 * i, tuple(tip), tip[2] - 0.07)
        s.handle((0.0, 0.0, -s.offset))
        s.update(0.04 * i, 0.0)
        tip[2] = 0.12 - 0.5 * s.offset                         # the tool follows the handle
    assert s.offset == pytest.approx(0.012 * 49 * 0.04, rel=0.02)
    before = s.offset
    for i in range(50, 150):                                  # the tool stops following: slack more at most
        s.observe(0.04 * i, tuple(tip), tip[2] - 0.07)
        s.handle((0.0, 0.0, -s.offset))
        s.update(0.04 * i, 0.0)
    assert before < s.offset <= before + 0.012 * 1.0 + 0.006 + 1e-9   # + what the window still saw following
    s.observe(6.04, (0.0, 0.0, 0.075), 0.005)                 # below the working height: back up
    before = s.offset
    s.update(6.08, 0.0)
    assert s.offset < before


@pytest.mark.parametrize('kw', [{'depth': -0.001}, {'speed': float('nan')}, {'site': (0.0,)},
                                {'hover': -0.01}, {'scale': 0.0}])
def test_bad_parameters_are_rejected(kw):
    with pytest.raises(ValueError):
        DipServo(**kw)


def test_a_dip_begun_blind_is_skipped_without_a_jump():
    s = DipServo()
    m = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12, servo=s)
    ref = ScriptedMotion(home=(-0.12, 0.0, 0.07), dip_depth=0.12, dip_period=0.0)
    m(6.0)
    s.observe(6.5, (0.0, 0.0, 0.1), 0.03)
    assert m(7.0).position == pytest.approx(ref(7.0).position)      # same dip: still skipped, on the path
    m(15.0)                                                          # between dips
    s.observe(25.0, (0.0, 0.0, 0.1), 0.03)
    assert m(27.0).position != pytest.approx(ref(27.0).position)    # next dip: servoed


class LeadLimitedTeleop(object):
    """The SARAS chain as velocity_integrator sees it: from ``engage`` [s] the set-point integrates
    SCALE x the handle's motion, at most ``max_lead`` [m] from the measured tip; the arm reaches the
    set-point ``lag`` [s] later; a lead saturated for longer than ``max_stall`` [s] is the "arm not
    following" hold (counted here, not simulated)."""

    def __init__(self, start, lag, engage=0.0, max_lead=0.003, count_from=0.0):
        self.setpoint, self.lag, self.engage, self.max_lead = list(start), lag, engage, max_lead
        self.count_from = count_from            # [s] stalls counted from then on
        self.history = collections.deque([(-1e9, tuple(start))])
        self.last, self.stall, self.worst_stall = None, 0.0, 0.0

    def tip(self, t):
        while len(self.history) > 1 and self.history[1][0] <= t - self.lag:
            self.history.popleft()
        return self.history[0][1]

    def step(self, t, dt, handle):
        if self.last is not None and t >= self.engage:
            measured = self.tip(t)
            nxt = [s + SCALE * (h - l) for s, h, l in zip(self.setpoint, handle, self.last)]
            d = [n - m for n, m in zip(nxt, measured)]
            n = sum(v * v for v in d) ** 0.5
            allowed = max(self.max_lead, sum((s - m) ** 2 for s, m in zip(self.setpoint, measured)) ** 0.5)
            if n > self.max_lead and n > allowed:
                nxt = [m + v * allowed / n for m, v in zip(measured, d)]
                self.stall += dt
            else:
                self.stall = 0.0
            if t >= self.count_from:
                self.worst_stall = max(self.worst_stall, self.stall)
            self.setpoint = nxt
        self.last = handle
        self.history.append((t, tuple(self.setpoint)))


def surgeon(height, lag, engage=0.0, duration=60.0, obs_delay=0.1):
    """touchball_console_sim's defaults (dip every 12 s for 8 s from 5 s, pace 0.35) through the
    stand-in; returns (teleoperation, [(t, tip signed distance, dip weight)])."""
    s = DipServo(depth=0.003, site=(0.0, 0.012), hover=0.012, speed=0.012)
    m = ScriptedMotion(home=(-0.10, 0.0, 0.08), dip_period=12.0, dip_duration=8.0, dip_start=5.0, servo=s,
                       pace=0.35)
    arm = LeadLimitedTeleop((0.005, 0.032, TISSUE_Z + height), lag, engage, count_from=17.0)
    t, dt, next_obs, log = 0.0, 0.004, 0.0, []
    while t < duration:
        arm.step(t, dt, m(t).position)
        if t >= next_obs:                                     # the arm's pose flows before the teleoperation engages
            seen = arm.tip(t - obs_delay)
            s.observe(t, seen, seen[2] - TISSUE_Z)
            next_obs = t + 1.0 / 30
        log.append((t, arm.tip(t)[2] - TISSUE_Z, m.dip_weight(t)))
        t += dt
    return arm, log


def dip_and_between(log, k):
    """Deepest tip in dip k (from 5 + 12 k s) and lowest tip in the 2.5 s before the next dip [m]."""
    dip = [sd for (t, sd, _) in log if 5.0 + 12.0 * k <= t < 13.0 + 12.0 * k]
    between = [sd for (t, sd, _) in log if 14.5 + 12.0 * k <= t < 17.0 + 12.0 * k]
    return min(dip), min(between)


@pytest.mark.parametrize('lag', [0.15, 0.3])
@pytest.mark.parametrize('height', [0.02, 0.05, 0.08])
def test_working_height_and_dips_through_a_lagging_lead_limited_teleoperation(lag, height):
    """Tool starting 2-8 cm above the tissue, an arm 0.15-0.3 s behind a set-point limited to 3 mm of
    lead: every dip from the second on presses 2-5.5 mm, the tool is off the tissue between dips,
    and once the tool works near the tissue (second dip on) the lead never saturates for the
    teleoperation's 1 s "arm not following" limit."""
    arm, log = surgeon(height, lag)
    for k in range(1, 4):
        deepest, lowest = dip_and_between(log, k)
        assert -0.0055 <= deepest <= -0.002, (k, deepest)
        assert lowest > 0.003, (k, lowest)
    assert arm.worst_stall < 1.0, arm.worst_stall


@pytest.mark.parametrize('engage', [3.0, 9.0, 20.0])          # 9: in the middle of the first dip
def test_dips_press_whenever_the_teleoperation_engages(engage):
    arm, log = surgeon(0.05, 0.3, engage=engage)
    first = int((engage - 5.0) // 12.0) + 2                   # the second dip after the engagement
    for k in range(first, 4):
        assert -0.0055 <= dip_and_between(log, k)[0] <= -0.002, k


def test_a_slower_arm_still_presses():
    """0.45 s of lag (the 90th percentile measured in loaded demos): the lead saturates now and then
    (a hold and a clutch in the platform), the dips still press."""
    _, log = surgeon(0.05, 0.45)
    for k in range(1, 4):
        assert -0.006 <= dip_and_between(log, k)[0] <= -0.002, k
