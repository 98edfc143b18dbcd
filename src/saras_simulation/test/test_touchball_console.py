"""Console simulator core: mass-damper against closed-form solutions, calibration, replay,
command handling and the packet stream."""
import math

import pytest

from saras_drivers import touchball_protocol as tp
from saras_simulation.touchball_console import (ConsoleCalibration, HandDeviceModel, Intention,
                                             ScriptedMotion, TouchballConsole, TrajectoryReplay,
                                             quat_from_rpy)


def test_free_mass_damper_matches_exponential_solution():
    # k = 0: m v' = F - b v  =>  v(t) = F/b (1 - exp(-b t / m)), x(t) = F/b (t - m/b (1 - exp(-b t/m)))
    m, b, F = 0.25, 2.0, 1.0
    model = HandDeviceModel(mass=m, hand_stiffness=0.0, hand_damping=0.0, damping=b, max_step=1e-5)
    model.reset((0.0, 0.0, 0.0))
    for _ in range(100):
        model.step(0.005, (0.0, 0.0, 0.0), (F, 0.0, 0.0))
    t = 0.5
    assert model.v[0] == pytest.approx(F / b * (1 - math.exp(-b * t / m)), rel=1e-3)
    assert model.x[0] == pytest.approx(F / b * (t - m / b * (1 - math.exp(-b * t / m))), rel=1e-3)


def test_hand_spring_static_deflection():
    model = HandDeviceModel(hand_stiffness=300.0)
    target = (0.01, 0.02, 0.03)
    for _ in range(5000):
        x = model.step(0.001, target, (0.0, 0.0, -1.5))
    assert x == pytest.approx((0.01, 0.02, 0.03 - 1.5 / 300.0), abs=1e-7)


def test_model_parameter_validation():
    with pytest.raises(ValueError):
        HandDeviceModel(mass=0.0)
    with pytest.raises(ValueError):
        HandDeviceModel(damping=-1.0)


def test_clip_range_calibration():
    cal = ConsoleCalibration(clip_max=1.2)
    cal.calibrate_clip([0.20, 0.22, 0.21], [0.80, 0.81, 0.79])
    assert cal.clip_angle(0.21) == pytest.approx(0.0)
    assert cal.clip_angle(0.80) == pytest.approx(1.2)
    assert cal.clip_angle(0.505) == pytest.approx(0.6)
    assert cal.clip_angle(2.0) == 1.2 and cal.clip_angle(-1.0) == 0.0
    with pytest.raises(ValueError):
        cal.calibrate_clip([0.5], [0.5])


def test_pose_calibration_reads_reference():
    cal = ConsoleCalibration()
    raw_p, raw_q = (0.1, -0.05, 0.2), quat_from_rpy(0.1, -0.2, 0.3)
    ref_p, ref_q = (0.0, 0.0, 0.1), quat_from_rpy(0.0, 0.0, 0.5)
    cal.calibrate_pose(raw_p, raw_q, ref_p, ref_q)
    p, q = cal.apply(raw_p, raw_q)
    assert p == pytest.approx(ref_p) and q == pytest.approx(ref_q, abs=1e-12)


def test_quat_from_rpy_matches_rotation_matrix():
    r, p, y = 0.3, -0.4, 1.1
    qx, qy, qz, qw = quat_from_rpy(r, p, y)
    # element (2,0) of Rz Ry Rx = -sin(p); element (1,0) = cos(p) sin(y)
    assert 2 * (qx * qz - qw * qy) == pytest.approx(-math.sin(p))
    assert 2 * (qx * qy + qw * qz) == pytest.approx(math.cos(p) * math.sin(y))


def test_replay_interpolates(tmp_path):
    path = tmp_path / 'rec.csv'
    cols = ['t'] + ['left_%s' % c for c in ('x', 'y', 'z', 'qx', 'qy', 'qz', 'qw', 'clip', 'clutch', 'clip_button')]
    path.write_text(','.join(cols) + '\n' + '0,0,0,0,0,0,0,1,0,0,0\n' + '1,0.1,0,0.2,0,0,1,0,1,1,0\n'
                    + '2,0,0,0,0,0,0,1,0,0,0\n')
    rep = TrajectoryReplay.from_csv(str(path), 'left')
    it = rep(0.5)
    assert it.position == pytest.approx((0.05, 0.0, 0.1))
    assert it.orientation == pytest.approx((0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)))
    assert it.clip_raw == pytest.approx(0.5) and not it.clutch
    assert rep(1.5).clutch and rep(2.5).position == pytest.approx((0.05, 0.0, 0.1))   # loops
    with pytest.raises(ValueError):
        TrajectoryReplay.from_csv(str(path), 'right')
    bad = tmp_path / 'bad.csv'
    bad.write_text(','.join(cols) + '\n0,a,0,0,0,0,0,1,0,0,0\n')
    with pytest.raises(ValueError, match='line 2'):
        TrajectoryReplay.from_csv(str(bad), 'left')


KEY = bytes(range(32))
S = 0x0123456789ABCDEF


def test_console_handshake_stream_and_forces():
    still = lambda t: Intention((0.0, 0.0, 0.1), (0, 0, 0, 1), 1.0)
    mac = tp.Mac(KEY)
    con = TouchballConsole((still, still), mac)
    for _ in range(10):
        devs = con.step(0.001)
    hello = con.packet(devs, 0.01)                           # unbound: a hello first
    _seq, _t, nonce = tp.unpack_hello(hello, mac)
    assert con.packet(devs, 0.01) is None                    # no state packet without a session
    assert con.handle_command(tp.pack_challenge(mac, S, nonce, 0, 0.0), con.t)
    pkt = tp.unpack_state(con.packet(devs, 0.02), mac, S)
    assert pkt.seq == 1
    assert pkt.devices[0].position == pytest.approx((0, 0, 0.1))
    # a force command on the left device pushes it by F/k at equilibrium; right unaffected
    push = (tp.DeviceCommand((0.0, 0.0, 3.0), (0, 0, 0), True), tp.ZERO_COMMAND)
    cmd = tp.pack_command(mac, S, 1, 0.0, push)
    assert not con.handle_command(cmd[:-1], 0.0)
    assert not con.handle_command(tp.pack_command(tp.Mac(bytes(32)), S, 1, 0.0, push), 0.0)   # forged
    assert con.commands_rejected == 2
    for k in range(3000):
        con.handle_command(tp.pack_command(mac, S, k + 2, 0.0, push), con.t)
        devs = con.step(0.001)
    assert devs[0].position[2] == pytest.approx(0.1 + 3.0 / 300.0, abs=1e-5)
    assert devs[1].position[2] == pytest.approx(0.1, abs=1e-9)
    for _ in range(3000):                                      # command stops => force times out
        devs = con.step(0.001)
    assert devs[0].position[2] == pytest.approx(0.1, abs=1e-5)


def test_scripted_motion_is_smooth_and_bounded():
    m = ScriptedMotion(clutch_period=4.0, clutch_duration=1.0)
    prev = m(0.0)
    clutch_seen = False
    for k in range(1, 5000):
        it = m(k * 0.001)
        step = math.sqrt(sum((a - b) ** 2 for a, b in zip(it.position, prev.position)))
        assert step < 0.001 * 0.5                             # < 0.5 m/s
        assert 0.0 <= it.clip_raw <= 1.0
        assert sum(x * x for x in it.orientation) == pytest.approx(1.0)
        clutch_seen |= it.clutch
        prev = it
    assert clutch_seen


class _Msg(object):
    """Duck-typed HapticDeviceState (no ROS import in core tests)."""

    class _V(object):
        def __init__(self, **kw):
            self.__dict__.update(kw)

    def __init__(self, x, clip, stale=False):
        self.pose = self._V(position=self._V(x=x, y=0.0, z=0.1),
                            orientation=self._V(x=0.0, y=0.0, z=0.0, w=1.0))
        self.clip_angle, self.clutch, self.clip_button, self.stale = clip, False, True, stale


def test_replay_from_recorded_states():
    msgs = [(10.0, _Msg(0.0, 0.0)), (10.5, _Msg(9.0, 9.0, stale=True)), (11.0, _Msg(0.1, 0.4)),
            (11.0, _Msg(5.0, 5.0)), (12.0, _Msg(0.0, 0.0))]
    rep = TrajectoryReplay.from_states(msgs, loop=False)
    assert rep.duration == 2.0
    it = rep(0.5)
    assert it.position == pytest.approx((0.05, 0.0, 0.1)) and it.clip_raw == pytest.approx(0.2)
    assert it.clip_button


def test_scripted_motion_dips_into_the_tissue_and_returns():
    m = ScriptedMotion(home=(-0.1, 0.0, 0.08), amplitude=(0.02, 0.03, 0.015), dip_depth=0.12, dip_period=20.0,
                       dip_duration=8.0, dip_start=5.0)
    assert m.dip_weight(4.9) == 0.0 and m(4.9).position[2] > 0.06
    held = m(9.0).position                      # middle of the dip: held at the start point, lowered
    assert held == pytest.approx((-0.1, 0.03, 0.08 - 0.12))
    assert 0.0 < m.dip_weight(6.0) < 1.0        # smooth ramp
    assert m.dip_weight(13.5) == 0.0            # back on the path
    assert m(29.0).position == pytest.approx(held)  # periodic
    assert ScriptedMotion(dip_period=0.0).dip_weight(9.0) == 0.0
