"""Four-timestamp clock offset core (saras_bringup.clock_offset)."""
import random

import pytest

from saras_bringup.clock_offset import (OK, STALE, WARN, ClockMonitorCore, Exchange,
                                        MachineClock, MonitorConfig, best_of)


def exchange(t1, offset, up, processing, down):
    """An exchange with a responder whose clock is `offset` ahead; one-way delays up/down."""
    t2 = t1 + up + offset
    t3 = t2 + processing
    t4 = t3 - offset + down
    return Exchange(t1, t2, t3, t4)


@pytest.mark.parametrize('offset', [0.0, 0.005, 0.050, -0.080, 12.5])
def test_symmetric_exchange_gives_exact_offset_and_delay(offset):
    e = exchange(100.0, offset, up=0.0004, processing=0.003, down=0.0004)
    assert e.offset == pytest.approx(offset, abs=1e-9)
    assert e.delay == pytest.approx(0.0008, abs=1e-9)


def test_asymmetry_biases_by_half_of_it():
    e = exchange(100.0, 0.010, up=0.001, processing=0.0, down=0.005)
    assert e.offset == pytest.approx(0.010 - 0.002, abs=1e-9)
    assert abs(e.offset - 0.010) <= e.delay / 2


def test_minimum_delay_filter_rejects_queued_exchanges():
    rng = random.Random(1)
    true_offset = -0.080
    exchanges = []
    for i in range(16):
        base = 0.0002
        up = base + (rng.uniform(0.0, 0.020) if i != 7 else 0.0)
        down = base + (rng.uniform(0.0, 0.020) if i != 7 else 0.0)
        exchanges.append(exchange(float(i), true_offset, up, 0.001, down))
    best = best_of(exchanges)
    assert best is exchanges[7]
    assert best.offset == pytest.approx(true_offset, abs=1e-9)
    worst = max(abs(e.offset - true_offset) for e in exchanges)
    assert worst > 0.001  # the filter matters: a random exchange is off by more than 1 ms


def test_machine_clock_window_slides():
    clock = MachineClock(window=2)
    clock.add(exchange(0.0, 0.0, 0.0001, 0.0, 0.0001))  # best, then pushed out
    clock.add(exchange(1.0, 0.0, 0.001, 0.0, 0.001))
    clock.add(exchange(2.0, 0.0, 0.002, 0.0, 0.002))
    assert clock.samples == 2 and clock.count == 3
    assert clock.best().delay == pytest.approx(0.002)
    assert best_of([]) is None
    with pytest.raises(ValueError):
        MachineClock(0)


def feed(core, machine, offset, t1, n=8, up=0.0003, down=0.0003):
    for k in range(n):
        t = t1 + 0.01 * k
        rid = core.new_request(t)
        e = exchange(t, offset, up, 0.0005, down)
        assert core.on_reply(rid, machine, e.t2, e.t3, e.t4) is not None


def test_monitor_rates_machines_against_the_threshold():
    core = ClockMonitorCore(MonitorConfig(threshold_s=0.002), expected=['dvrk_pc'])
    feed(core, 'teleop_pc', 0.0015, 10.0)
    feed(core, 'saras_left', -0.0025, 10.0)
    assert core.machines == ['dvrk_pc', 'saras_left', 'teleop_pc']
    ok = core.status('teleop_pc', 10.2)
    assert ok.level == OK and ok.offset_s == pytest.approx(0.0015) and ok.samples == 8
    warn = core.status('saras_left', 10.2)
    assert warn.level == WARN and 'above 2.000 ms' in warn.message
    assert core.status('dvrk_pc', 10.2).level == STALE  # expected, never answered
    stale = core.status('teleop_pc', 10.1 + 3.5)
    assert stale.level == STALE and stale.offset_s == pytest.approx(0.0015)


def test_monitor_discards_unknown_expired_and_slow_replies():
    core = ClockMonitorCore(MonitorConfig(timeout_s=1.0, max_delay_s=0.1))
    assert core.on_reply(12345, 'x', 1.0, 1.0, 1.0) is None  # never requested
    rid = core.new_request(0.0)
    core.new_request(5.0)  # expires rid
    assert core.on_reply(rid, 'x', 0.1, 0.1, 0.2) is None
    slow = core.new_request(10.0)
    assert core.on_reply(slow, 'x', 10.1, 10.1, 10.3) is None  # round trip 0.3 s
    backwards = core.new_request(20.0)
    assert core.on_reply(backwards, 'x', 20.5, 20.4, 20.0) is None  # negative delay
    assert core.discarded == 4 and core.machines == []


@pytest.mark.parametrize('kwargs', [{'threshold_s': 0.0}, {'window': 0}, {'timeout_s': -1.0}])
def test_monitor_config_is_validated(kwargs):
    with pytest.raises(ValueError):
        MonitorConfig(**kwargs)
