"""SARAS arm model: IK/FK round trip, RCM invariance, velocity limit, rejection => no motion."""
import math

import numpy as np
import pytest

from saras_drivers import saras_arm_kinematics as sak
from saras_drivers import saras_arm_protocol as proto
from saras_simulation.saras_arm_model import SarasArmModel, TargetRejected, matrix_to_quat, quat_to_matrix

#: A Positioning-Arm set-up pose [rad] (independent of saras_description's YAML).
PA = [0.0, 0.5, 0.0, 1.3, 0.0, 1.0, 0.0]


@pytest.fixture(params=['left', 'right'])
def model(request):
    return SarasArmModel(sak.load(request.param, PA), max_velocity=1.0, insertion_ratio=0.05)


def _reachable(m, rng):
    q = m.q.copy()
    q[:4] = m.lower[:4] + rng.uniform(0.1, 0.9, 4) * (m.upper[:4] - m.lower[:4])
    return q, m.tip_in_base(q)


def test_target_reached_and_rcm_invariant(model):
    rng = np.random.RandomState(3)
    rcm = model.rcm_position()
    for _ in range(5):
        q, t = _reachable(model, rng)
        model.set_target(t[:3, 3])
        for _ in range(3000):
            model.step(0.002)
            if not model.moving:
                break
        tip = model.tip_in_base()
        assert np.linalg.norm(tip[:3, 3] - t[:3, 3]) < 1e-9
        # shaft line (tip z axis) passes through the RCM: distance from RCM to the line is 0
        d = rcm - tip[:3, 3]
        axis = tip[:3, 2]
        assert np.linalg.norm(d - d.dot(axis) * axis) < 1e-9


def test_velocity_limit_and_synchronised_motion(model):
    rng = np.random.RandomState(5)
    q, t = _reachable(model, rng)
    model.set_max_velocity(0.5)
    model.set_target(t[:3, 3])
    limits = model.joint_velocity_limits()
    assert limits[2] == pytest.approx(0.5 * 0.05)
    prev = model.q.copy()
    start = model.q.copy()
    peak = np.zeros(6)
    steps = 0
    while model.moving and steps < 100000:
        model.step(0.003)                              # 2 sub-steps of 1.5 ms each
        peak = np.maximum(peak, np.abs(model.q - prev) / 0.003)
        prev = model.q.copy()
        steps += 1
    assert np.all(peak <= limits * (1 + 1e-9))
    assert np.max(peak / limits) > 0.999              # the slowest-to-arrive joint saturates
    # straight line in joint space: every intermediate point is collinear
    dq = model.q - start
    assert np.linalg.norm(dq) > 0


def test_rcm_violating_target_rejected_without_motion(model):
    rcm = model.rcm_position()
    inward = model.kin.rcm_in_base()[:3, :3].dot(model._inward)
    before_q, before_target = model.q.copy(), model.target.copy()
    for bad in (rcm - 0.05 * inward, rcm + np.array([0.0, 0.0, 0.0]), rcm - 0.001 * inward):
        with pytest.raises(TargetRejected) as e:
            model.set_target(bad)
        assert e.value.code == proto.RCM_VIOLATION
    with pytest.raises(TargetRejected) as e:
        model.set_target(rcm + 0.5 * inward)           # beyond max insertion
    assert e.value.code == proto.WORKSPACE
    model.step(0.1)
    assert np.array_equal(model.q, before_q) and np.array_equal(model.target, before_target)


def test_orientation_axis_check_and_roll(model):
    rng = np.random.RandomState(7)
    q, t = _reachable(model, rng)
    good = matrix_to_quat(t[:3, :3])
    model.set_target(t[:3, 3], good)
    assert model.target[3] == pytest.approx(q[3] if abs(q[3]) < math.pi else q[3], abs=1e-9)
    flipped = matrix_to_quat(t[:3, :3].dot(np.diag([1.0, -1.0, -1.0])))   # shaft reversed
    with pytest.raises(TargetRejected) as e:
        model.set_target(t[:3, 3], flipped)
    assert e.value.code == proto.RCM_VIOLATION


def test_roll_about_the_shaft_follows_the_target_orientation(model):
    """The Simball handle's rotation reaches the arm as the target_pose orientation; the arm realises
    its component about the instrument shaft (tool z) as roll and ignores the rest (the shaft
    direction is set by the RCM)."""
    rng = np.random.RandomState(13)
    q, t = _reachable(model, rng)
    model.set_target(t[:3, 3], matrix_to_quat(t[:3, :3]))
    while model.moving:
        model.step(0.01)
    r0 = model.tip_in_base()[:3, :3]

    def rot(axis, a):
        c, s = math.cos(a), math.sin(a)
        return {'z': np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]),
                'x': np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])}[axis]
    for desired, expect in ((r0.dot(rot('z', 0.3)), 0.3),                       # pure roll
                            (r0.dot(rot('z', -0.2)).dot(rot('x', 0.1)), -0.2)):  # roll + tilt: tilt ignored
        model.set_target(t[:3, 3], matrix_to_quat(desired))
        while model.moving:
            model.step(0.01)
        r = model.tip_in_base()[:3, :3]
        assert np.allclose(r[:, 2], r0[:, 2], atol=1e-9)               # shaft unchanged
        rel = r0.T.dot(r)
        assert math.atan2(rel[1, 0], rel[0, 0]) == pytest.approx(expect, abs=0.01)


def test_clip_and_max_velocity_validation(model):
    model.set_clip(jaw=0.5, roll=None)
    assert model.target[5] == 0.5
    with pytest.raises(TargetRejected):
        model.set_clip(jaw=10.0)
    assert model.target[5] == 0.5
    for v in (0.0, -1.0, float('nan'), 100.0):
        with pytest.raises(TargetRejected) as e:
            model.set_max_velocity(v)
        assert e.value.code == proto.BAD_VALUE
    with pytest.raises(ValueError):
        SarasArmModel(model.kin, min_rate=100.0)


def test_jaw_moves_at_its_own_speed_independently_of_the_arm(model):
    jaw_v = model.jaw_velocity
    model.set_clip(jaw=model.lower[5])
    while model.moving:
        model.step(0.01)
    rng = np.random.RandomState(11)
    q, t = _reachable(model, rng)
    model.set_max_velocity(0.2)
    model.set_target(t[:3, 3])
    model.set_clip(jaw=model.upper[5])                 # open fully while the arm moves slowly
    arm_alone = SarasArmModel(model.kin, max_velocity=0.2, insertion_ratio=0.05, initial_joints=model.q.copy())
    arm_alone.set_target(t[:3, 3])
    jaw_prev, steps = model.q[5], 0
    while model.moving and steps < 100000:
        model.step(0.003)
        arm_alone.step(0.003)
        assert model.q[5] - jaw_prev <= jaw_v * 0.003 * (1 + 1e-9)
        assert np.array_equal(model.q[:5], arm_alone.q[:5])   # the jaw neither slows nor waits for the arm
        jaw_prev = model.q[5]
        steps += 1
        if steps * 0.003 >= (model.upper[5] - model.lower[5]) / jaw_v + 0.01:
            assert model.q[5] == model.upper[5]        # the jaw arrived on its own schedule
    assert np.array_equal(model.q, model.target)
    with pytest.raises(ValueError):
        SarasArmModel(model.kin, jaw_velocity=0.0)


def test_quaternion_matrix_round_trip():
    rng = np.random.RandomState(1)
    for _ in range(50):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        q = q if q[3] >= 0 else -q
        assert np.allclose(matrix_to_quat(quat_to_matrix(q)), q, atol=1e-12)


@pytest.mark.parametrize('side', ['left', 'right'])
@pytest.mark.parametrize('dt', [0.002, 0.1])
def test_tip_speed_limit_on_a_far_target(side, dt):
    """A target far from the arm (a late set-point, a stalled commander) is approached at the
    controller's tool-tip speed limit, not at the motors' speed; it is still reached."""
    limit = 0.05
    free = SarasArmModel(sak.load(side, PA), max_velocity=1.0, insertion_ratio=0.05)
    m = SarasArmModel(sak.load(side, PA), max_velocity=1.0, insertion_ratio=0.05, max_tip_speed=limit)
    rng = np.random.RandomState(5)
    fastest = 0.0
    for _ in range(3):
        _, t = _reachable(m, rng)
        m.set_target(t[:3, 3])
        free.q = m.q.copy()
        free.set_target(t[:3, 3])
        free.step(dt)
        fastest = max(fastest, np.linalg.norm(free.tip_in_base()[:3, 3] - m.tip_in_base()[:3, 3]) / dt)
        peak = 0.0
        for _ in range(int(30.0 / dt)):
            before = m.tip_in_base()[:3, 3]
            m.step(dt)
            peak = max(peak, np.linalg.norm(m.tip_in_base()[:3, 3] - before) / dt)
            if not m.moving:
                break
        assert not m.moving
        assert np.linalg.norm(m.tip_in_base()[:3, 3] - t[:3, 3]) < 1e-9
        assert limit * 0.9 < peak <= limit * (1 + 1e-6)    # the limit holds, and is used ...
    assert fastest > 1.5 * limit           # ... where the motors alone would have been faster


def test_tip_speed_limit_validated():
    with pytest.raises(ValueError):
        SarasArmModel(sak.load('left', PA), max_tip_speed=0.0)
    with pytest.raises(ValueError):
        SarasArmModel(sak.load('left', PA), max_tip_speed=float('nan'))
