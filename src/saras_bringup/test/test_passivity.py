"""Port energies from recorded port variables (saras_bringup.passivity)."""
import math

import pytest

from saras_bringup.passivity import (contact_summary, energy_balance, port_energy, port_power, time_to_hold,
                                    tracking_error, travel, engaged_windows, device_windows)


def test_port_power_holds_the_latest_conjugate():
    actions = [(0.0, (1, 0, 0, 0, 0, 0)), (0.1, (2, 0, 0, 0, 0, 0)), (0.2, (2, 0, 0, 0, 0, 0))]
    conj = [(0.05, (3, 0, 0, 0, 0, 0)), (0.15, (-1, 0, 0, 0, 0, 0))]
    p = port_power(actions, conj)
    assert [round(x[1], 9) for x in p] == [0.0, 6.0, -2.0]
    assert [round(x[2], 9) for x in p] == [0.1, 0.1, 0.1]


def test_passive_when_net_energy_stays_below_the_initial_tank_energy():
    # 1 W out for 5 s, then 1 W in for 5 s: net peaks at 5 J
    port = [(0.01 * i, 1.0 if i < 500 else -1.0, 0.01) for i in range(1000)]
    ok = energy_balance([port], e0=6.0)
    assert ok['delivered_J'] == pytest.approx(5.0) and ok['injected_J'] == pytest.approx(5.0)
    assert ok['entered_J'] == pytest.approx(11.0)
    assert ok['net_max_J'] == pytest.approx(5.0) and ok['passive']
    bad = energy_balance([port], e0=4.0)
    assert not bad['passive'] and bad['margin_J'] == pytest.approx(-1.0)
    # energy generated with nothing stored (tanks bypassed) is a violation
    assert not energy_balance([port], e0=0.0)['passive']
    assert energy_balance([[(0.0, -1.0, 1.0)]], e0=0.0)['passive']


def test_tracking_error_scaled_master_vs_slave():
    master = [(0.1 * i, (0.01 * i, 0.0, 0.0)) for i in range(20)]
    slave = [(0.1 * i + 0.05, (0.005 * i + 0.001, 0.0, 0.0)) for i in range(20)]
    rms, mx = tracking_error(master, slave, scale=0.5)
    assert rms == pytest.approx(0.0, abs=1e-12) and mx == pytest.approx(0.0, abs=1e-12)
    rms, mx = tracking_error(master, slave, scale=1.0)
    assert mx == pytest.approx(0.095, abs=1e-9)
    assert math.isnan(tracking_error([], slave, 1.0)[0])


def test_tracking_error_reanchors_on_the_clutch():
    # the master moves 10 mm while clutched (1-2 s); the slave stays: a re-index, not an error
    def m_at(t):
        return 0.01 * t + (0.01 if t >= 2.0 else 0.01 * (t - 1.0) if t >= 1.0 else 0.0)
    master = [(0.01 * i, (m_at(0.01 * i), 0.0, 0.0)) for i in range(300)]
    slave = [(0.01 * i + 0.005, (0.01 * (min(0.01 * i, 1.0) + max(0.0, 0.01 * i - 2.0)), 0.0, 0.0))
             for i in range(300)]
    states = [(0.0, (False, False)), (1.0, (True, False)), (2.0, (False, False))]
    windows = engaged_windows(states, 3.0)
    assert windows == [(0.0, 1.0), (2.0, 3.0)]
    rms, mx = tracking_error(master, slave, 1.0, windows)
    assert mx < 2e-4
    # without the windows the re-index counts as a 10 mm error
    assert tracking_error(master, slave, 1.0)[1] > 0.0099
    # a stale link ends a window as the clutch does
    assert engaged_windows([(0.0, (False, False)), (0.5, (False, True))], 1.0) == [(0.0, 0.5)]
    assert math.isnan(tracking_error(master, slave, 1.0, [])[0])


def test_device_windows_merge_clutch_stale_and_hold():
    states = [(0.0, (False, False)), (1.0, (True, False)), (1.2, (False, False)), (3.0, (False, True)),
              (3.1, (False, False))]
    holds = [(0.5, False), (2.0, True), (3.5, False)]      # a hold from 2.0 s until the clutch-less 3.5 s
    assert device_windows(states, holds, 5.0) == [(0.0, 1.0), (1.2, 2.0), (3.5, 5.0)]
    assert device_windows([], [], 5.0) == []


def test_time_to_hold():
    sp = [(0.01 * i, (min(0.01 * i, 3.3) * 1e-2, 0.0, 0.0)) for i in range(600)]
    assert time_to_hold(sp, 3.0) == pytest.approx(0.3, abs=0.011)
    moving = [(0.01 * i, (0.01 * i, 0.0, 0.0)) for i in range(600)]
    assert time_to_hold(moving, 3.0) is None


def test_port_energy_splits_delivered_and_injected():
    port = [(0.01 * i, 2.0 if i < 100 else -0.5, 0.01) for i in range(300)]
    d, i = port_energy(port)
    assert d == pytest.approx(2.0) and i == pytest.approx(1.0)
    assert port_energy([]) == (0, 0)


def test_contact_summary_peak_and_time_in_contact():
    forces = [(0.1 * i, (0.0, 0.0, 3.0 if 10 <= i < 30 else 0.0)) for i in range(50)]
    forces[15] = (1.5, (4.0, 0.0, -3.0))
    peak, held = contact_summary(forces)
    assert peak == pytest.approx(5.0) and held == pytest.approx(2.0)
    assert contact_summary([]) == (0.0, 0)


def test_travel_is_the_largest_distance_from_the_start():
    assert travel([(0.0, (1.0, 0.0, 0.0)), (1.0, (1.0, 0.3, 0.4)), (2.0, (1.0, 0.0, 0.1))]) == pytest.approx(0.5)
    assert travel([]) == 0.0
