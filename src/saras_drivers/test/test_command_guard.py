"""CommandGuard and JawGuard: the SARAS arm driver's own target and jaw checks (no ROS)."""
import pytest

from saras_drivers.command_guard import CommandGuard, JawGuard


def guard(**kw):
    args = dict(workspace_min=(-0.2, -0.2, -0.2), workspace_max=(0.2, 0.2, 0.2), max_speed=0.06,
                max_jump=0.001)
    args.update(kw)
    g = CommandGuard(**args)
    g.measured((0.0, 0.0, 0.0), 0.0)
    return g


def test_zero_and_future_stamps_are_rejections_not_bypasses():
    g = guard()
    assert g.check((0.0, 0.0, 0.0), None, 0.0) == (False, 'zero_stamp')
    assert g.check((0.0, 0.0, 0.0), -0.5, 0.0) == (False, 'future_stamp')
    assert g.check((0.0, 0.0, 0.0), 0.5, 0.0) == (False, 'stale')
    assert g.check((0.0, 0.0, 0.0), 0.005, 0.0) == (True, '')
    assert g.rejected['zero_stamp'] == 1 and g.rejected['future_stamp'] == 1


def test_workspace_box():
    g = guard()
    assert g.check((0.0, 0.0, 0.25), 0.0, 0.0) == (False, 'workspace')
    assert g.check((0.0, float('nan'), 0.0), 0.0, 0.0)[0] is False


def test_first_target_must_be_at_the_measured_pose():
    g = guard()
    assert g.check((0.0134, 0.0, 0.0), 0.0, 0.01) == (False, 'jump')  # live set-point 13.4 mm away
    assert g.check((0.0008, 0.0, 0.0), 0.0, 0.01) == (True, '')
    g2 = CommandGuard((-1, -1, -1), (1, 1, 1), 0.06, 0.001)
    assert g2.check((0.0, 0.0, 0.0), 0.0, 0.0) == (False, 'no_measurement')
    g.measured((0.0, 0.0, 0.0), 0.0)
    assert g.check((0.0, 0.0, 0.0), 0.0, 1.0) == (False, 'no_measurement')  # measurement 1 s old
    g3 = CommandGuard((-1, -1, -1), (1, 1, 1), 0.06, 0.001, require_measurement=False)
    assert g3.check((0.5, 0.0, 0.0), 0.0, 0.0) == (True, '')     # link test without a state stream
    g3.sent((0.5, 0.0, 0.0), 0.0)
    assert g3.check((0.0, 0.0, 0.0), 0.0, 0.004) == (False, 'speed')


def test_speed_limit_per_step_and_spoofed_stream():
    g = guard()
    t, x = 0.0, 0.0
    assert g.check((x, 0.0, 0.0), 0.0, t)[0]
    g.sent((x, 0.0, 0.0), t)
    for _ in range(250):                       # a 50 mm/s stream at 250 Hz passes
        t += 0.004
        x += 0.05 * 0.004
        assert g.check((x, 0.0, 0.0), 0.0, t) == (True, '')
        g.sent((x, 0.0, 0.0), t)
        # a spoofed target 2 cm deeper interleaved with it never passes
        assert g.check((x, 0.0, -0.02), 0.0, t + 0.002) == (False, 'speed')
    assert g.rejected['speed'] == 250
    # 10.7 mm in 0.2 s (53 mm/s average but one step): rejected
    assert g.check((x + 0.0107, 0.0, 0.0), 0.0, t + 0.004) == (False, 'speed')


def test_gap_and_reset_resynchronise_on_the_measured_pose():
    g = guard()
    g.check((0.0, 0.0, 0.0), 0.0, 0.0)
    g.sent((0.0, 0.0, 0.0), 0.0)
    g.measured((0.001, 0.0, 0.0), 1.0)
    # after a 1 s gap a target 5 mm from the measured pose is a jump even at 5 mm/s
    assert g.check((0.006, 0.0, 0.0), 0.0, 1.0) == (False, 'jump')
    assert g.check((0.0012, 0.0, 0.0), 0.0, 1.0) == (True, '')
    g.sent((0.0012, 0.0, 0.0), 1.0)
    g.reset()
    assert g.check((0.0014, 0.0, 0.0), 0.0, 1.001) == (True, '')  # within max_jump of 1 mm


@pytest.mark.parametrize('kw', [dict(max_speed=0.0), dict(max_jump=float('nan')),
                                dict(workspace_min=(0.3, 0.0, 0.0))])
def test_invalid_parameters(kw):
    with pytest.raises(ValueError):
        guard(**kw)


def test_jaw_guard_forwards_changed_commands_and_a_held_one_periodically():
    g = JawGuard('mesa_left/jaw', max_age=0.1, resend_period=0.25)
    assert g.check(['mesa_left/jaw'], [0.3], 0.01, 10.0) == (0.3, None)
    g.sent(0.3, 10.0)
    assert g.check(['mesa_left/jaw'], [0.3], 0.01, 10.1) == (None, None)   # held: not re-sent yet
    assert g.check(['mesa_left/jaw'], [0.3], 0.01, 10.3) == (0.3, None)    # ... but after resend_period
    assert g.check(['mesa_left/jaw'], [0.31], 0.01, 10.1) == (0.31, None)
    g.sent(0.31, 10.1)
    g.reset()                                                               # reconnection: send again
    assert g.check(['mesa_left/jaw'], [0.31], 0.01, 10.11) == (0.31, None)


def test_jaw_guard_rejects_bad_commands_with_a_reason():
    g = JawGuard('mesa_left/jaw', max_age=0.1)
    assert g.check(['mesa_right/jaw'], [0.3], 0.0, 1.0) == (None, 'invalid')
    assert g.check(['mesa_left/jaw', 'x'], [0.3, 0.1], 0.0, 1.0) == (None, 'invalid')
    assert g.check(['mesa_left/jaw'], [float('nan')], 0.0, 1.0) == (None, 'invalid')
    assert g.check(['mesa_left/jaw'], [float('inf')], 0.0, 1.0) == (None, 'invalid')
    assert g.check(['mesa_left/jaw'], [0.3], None, 1.0) == (None, 'zero_stamp')
    assert g.check(['mesa_left/jaw'], [0.3], -1.0, 1.0) == (None, 'future_stamp')
    assert g.check(['mesa_left/jaw'], [0.3], 0.5, 1.0) == (None, 'stale')
    assert g.rejected == {'invalid': 4, 'zero_stamp': 1, 'future_stamp': 1, 'stale': 1}
    for bad in (dict(max_age=0.0), dict(resend_period=float('nan'))):
        with pytest.raises(ValueError):
            JawGuard('mesa_left/jaw', **bad)


def test_a_burst_of_delayed_set_points_is_not_a_fast_motion():
    """Set-points that arrive together (a stalled host, a network burst) move as fast as their stamps
    say: accepted; a target whose stamp interval is as short as its arrival interval is still judged."""
    g = guard()
    assert g.check((0.0, 0.0, 0.0), 0.0, 0.0)[0]
    g.sent((0.0, 0.0, 0.0), 0.0, 0.0)
    now = 0.08                                   # four 40 mm/s set-points of the last 80 ms (0.8 mm apart), at once
    for k in range(1, 5):
        stamp = 0.02 * k
        x = 0.04 * stamp
        assert g.check((x, 0.0, 0.0), now - stamp, now) == (True, '')
        g.sent((x, 0.0, 0.0), now, stamp)
    # the same 3.2 mm jump without the stamps to justify it: too fast
    assert g.check((x + 0.0032, 0.0, 0.0), 0.0, now + 0.001) == (False, 'speed')
    # a forged stamp at the edge of the age window gains at most (max_age + max_future) * max_speed
    assert g.check((x + 0.0075, 0.0, 0.0), -0.02, now + 0.001) == (False, 'speed')
