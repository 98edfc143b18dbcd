"""Master console, teleoperation and CRTK arm cores of dvrk_sim (ROS-free)."""
import math
import os

import numpy as np
import pytest
import yaml

from saras_description import kinematics as desc
from saras_simulation import crtk_arm, dvrk_console, dvrk_kinematics, dvrk_sim_core

CONFIG = os.path.join(os.path.dirname(__file__), '..', 'config', 'dvrk_sim.yaml')


@pytest.fixture(scope='module')
def cfg():
    with open(CONFIG) as f:
        return yaml.safe_load(f)


def test_chains_match_the_urdf_model_and_jacobian_is_the_derivative():
    rng = np.random.default_rng(3)
    psm, ecm = dvrk_kinematics.psm_chain(), dvrk_kinematics.ecm_chain()
    for _ in range(10):
        q = rng.uniform(-0.6, 0.6, 6)
        q[2] = 0.12
        np.testing.assert_allclose(psm.fk(q), desc.psm_tip_in_base(q), atol=1e-12)
        np.testing.assert_allclose(ecm.fk(q[:4]), desc.ecm_tip_in_base(q[:4]), atol=1e-12)
        T, J = psm.fk(q, jacobian=True)
        for i in range(6):
            dq = q.copy()
            dq[i] += 1e-7
            np.testing.assert_allclose(J[:, i], dvrk_kinematics.pose_error(T, psm.fk(dq)) / 1e-7,
                                       atol=1e-5)


@pytest.mark.parametrize('chain, q0', [
    (dvrk_kinematics.psm_chain(), [0.1, -0.2, 0.12, 0.3, 0.2, -0.1]),
    (dvrk_kinematics.mtm_chain(), [0.2, -0.3, 0.4, 0.1, 0.2, -0.2, 0.3])])
def test_ik_reaches_a_5cm_offset_pose(chain, q0):
    T = chain.fk(np.array(q0))
    goal = T.copy()
    goal[:3, 3] += (0.05, -0.03, 0.02)
    q, residual = chain.ik(goal, q0)
    assert residual < 1e-6
    np.testing.assert_allclose(chain.fk(q), goal, atol=1e-5)


def test_teleop_scales_holds_while_clutched_and_reanchors_without_jump():
    tele = dvrk_console.Teleop(scale=0.2)
    mtm, psm = np.eye(4), np.eye(4)
    psm[:3, 3] = (0.0, 0.0, -0.12)
    assert np.allclose(tele.update(mtm, False, psm), psm)
    mtm2 = mtm.copy()
    mtm2[:3, 3] = (0.05, 0.0, 0.0)
    goal = tele.update(mtm2, False, psm)
    np.testing.assert_allclose(goal[:3, 3], (0.01, 0.0, -0.12))
    mtm3 = mtm2.copy()
    mtm3[:3, 3] = (0.15, 0.1, 0.0)                      # hand moves while clutched: PSM holds
    np.testing.assert_allclose(tele.update(mtm3, True, goal), goal)
    np.testing.assert_allclose(tele.update(mtm3, False, goal), goal)   # release: no jump
    mtm4 = mtm3.copy()
    mtm4[:3, 3] += (0.0, 0.05, 0.0)
    np.testing.assert_allclose(tele.update(mtm4, False, goal)[:3, 3], goal[:3, 3] + (0, 0.01, 0))


def test_pedal_events_only_on_change():
    ev = dvrk_console.PedalEvents()
    assert ev.update({'clutch': False, 'coag': False}) == {'clutch': False, 'coag': False}
    assert ev.update({'clutch': False, 'coag': False}) == {}
    assert ev.update({'clutch': True, 'coag': False}) == {'clutch': True}


def test_operating_state_machine():
    s = crtk_arm.OperatingState()
    assert s.ready
    s.command('disable')
    assert s.state == 'DISABLED' and not s.ready
    s.command('home')
    assert s.state == 'ENABLED' and s.homed
    s.command('unhome')
    assert not s.ready
    with pytest.raises(ValueError):
        s.command('fly')


def test_move_is_busy_then_idle_and_reaches_goal():
    chain = dvrk_kinematics.psm_chain()
    q0 = np.array([0.0, 0.0, 0.12, 0.0, 0.0, 0.0])
    arm = crtk_arm.CrtkArm('PSM1', chain, q0, 1.5, 3.0, jaw=crtk_arm.jaw_group(), client_timeout=1.0)
    arm.pop_events()
    goal = q0 + (0.17, -0.17, 0, 0, 0, 0)
    assert arm.move_jp(goal, 0.0)
    assert arm.pop_events() == [('ENABLED', True, True)]
    t, events = 0.0, []
    while t < 1.0:
        t += 0.01
        arm.step(t, q0)
        events += arm.pop_events()
    assert events == [('ENABLED', True, False)]
    np.testing.assert_allclose(arm.joints.q, goal)
    # zero-length move: still answers busy then idle (the client's wait() needs both)
    arm.move_jp(goal, t)
    arm.step(t + 0.01, q0)
    assert [e[2] for e in arm.pop_events()] == [True, False]


def test_disabled_arm_ignores_motion_and_client_timeout_rejoins_the_script():
    chain = dvrk_kinematics.psm_chain()
    q0 = np.array([0.0, 0.0, 0.12, 0.0, 0.0, 0.0])
    script = q0 + 0.1
    arm = crtk_arm.CrtkArm('PSM1', chain, q0, 1.5, 3.0, client_timeout=1.0, rejoin_time=0.5)
    arm.state_command('disable', 0.0)
    assert not arm.move_jp(q0 + 0.1, 0.0) and arm.rejected == 1
    arm.state_command('enable', 0.0)
    assert arm.servo_jp(q0, 0.0)
    q, _ = arm.step(0.5, script)
    np.testing.assert_allclose(q, q0)                    # client holds it
    qs = [arm.step(t, script)[0].copy() for t in np.arange(1.01, 1.7, 0.01)]
    np.testing.assert_allclose(qs[-1], script)           # back on the script
    assert max(np.abs(np.diff(qs, axis=0)).max(axis=1)) < 0.01   # blended, no jump
    assert arm.mode == crtk_arm.SCRIPTED


def test_psms_follow_the_mtms_and_hold_during_clutch(cfg):
    sim = dvrk_sim_core.ConsoleSim(cfg)
    from saras_simulation import dvrk_motion
    intent = dvrk_motion.DvrkSimCore.from_config(cfg)
    clutch_seen, worst = [], 0.0
    held = None
    for i in range(1200):                                # 12 s: one clutch at 6 .. 7.5 s
        t = i * 0.01
        out, pedals, _ = sim.step(t)
        if 'clutch' in pedals:
            clutch_seen.append((t, pedals['clutch']))
        tau = sim.script.task_time(t)[0]
        ref = intent.sample(tau)
        for p in ('PSM1', 'PSM2'):
            worst = max(worst, np.linalg.norm(out[p][2][:3, 3] - ref[p][1][:3, 3]))
        if 6.1 < t < 7.4:
            if held is None:
                held = out['PSM1'][2][:3, 3].copy(), out['MTMR'][2][:3, 3].copy()
            np.testing.assert_allclose(out['PSM1'][2][:3, 3], held[0], atol=1e-9)
    assert worst < 1e-3                                  # PSMs = the surgeon's intent
    assert [c for _, c in clutch_seen] == [False, True, False]
    assert np.linalg.norm(out['MTMR'][2][:3, 3] - held[1]) > 0.01   # the hand moved meanwhile


def test_node_parameters_shipped_config_is_valid_and_bad_values_are_named(cfg):
    from saras_common import params as prm
    p = prm.read(cfg, dvrk_sim_core.NODE_PARAMS)
    assert p['rate'] == 100.0 and p['max_catch_up'] >= 1 and p['publish_queue_size'] == 0
    assert prm.read({}, dvrk_sim_core.NODE_PARAMS)['link_tf_rate'] == 50.0    # defaults are valid
    for key, bad in (('rate', 0.5), ('max_catch_up', 2.5), ('crtk_ns', 'PSM'), ('publish_tf', 'yes'),
                     ('link_tf_rate', -1.0), ('robot_description_param', '/PSM1/robot_description')):
        with pytest.raises(prm.ParamError, match='~%s' % key):
            prm.read(dict(cfg, **{key: bad}), dvrk_sim_core.NODE_PARAMS)


def test_forward_pass_is_that_of_the_composed_elements():
    """Chain.fk (arithmetic on floats) against the product of its elements' 4x4 matrices."""
    rng = np.random.default_rng(5)
    for chain in (dvrk_kinematics.psm_chain(), dvrk_kinematics.ecm_chain(), dvrk_kinematics.mtm_chain()):
        for _ in range(5):
            q = rng.uniform(-1.0, 1.0, chain.n)
            T, i = np.eye(4), 0
            for e in chain.elements:
                if e[0] == 'fixed':
                    T = T @ e[1]
                    continue
                v = e[2] * q[i] + e[3]
                i += 1
                T = T @ (dvrk_kinematics._rot(e[1], v) if e[0] == 'r' else dvrk_kinematics._trans(e[1], v))
            np.testing.assert_allclose(chain.fk(q), T, atol=1e-12)
            np.testing.assert_allclose(chain.fk(list(q), jacobian=True)[0], T, atol=1e-12)
        with pytest.raises(ValueError):
            chain.fk(np.zeros(chain.n + 1))


@pytest.mark.parametrize('axis, angle', [((1, 0, 0), math.pi), ((0, 1, 1), math.pi), ((0, 0, 1), 0.3),
                                         ((1, -2, 0.5), 2.0), ((0, 1, 0), 0.0)])
def test_pose_error_is_the_translation_and_the_rotation_vector(axis, angle):
    from saras_common import transforms
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    T = np.eye(4)
    T[:3, 3] = [0.01, -0.02, 0.03]
    goal = np.eye(4)
    goal[:3, :3] = transforms.axis_angle(a, angle)[:3, :3]
    err = dvrk_kinematics.pose_error(T, goal, orientation_weight=0.5)
    np.testing.assert_allclose(err[:3], [-0.01, 0.02, -0.03], atol=1e-15)
    np.testing.assert_allclose(err[3:], 0.5 * angle * a, atol=1e-9)
