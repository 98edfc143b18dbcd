"""kinematics.py against an independent KDL chain built from the generated URDF XML."""
import math

import numpy as np
import pytest
from saras_description_testlib import UrdfTree

from saras_description import config as cfg
from saras_description import kinematics as k
from saras_description import urdf
from saras_common.transforms import quaternion_from_matrix, quaternion_to_matrix, rpy_to_matrix

N = 200
TOL = 1e-9


def _random(limits, rng, margin=0.0):
    return np.array([rng.uniform(lim.lower + margin, lim.upper - margin) for lim in limits.values()])


@pytest.fixture(scope='module')
def setups():
    return cfg.load_saras_arms()


@pytest.mark.parametrize('prefix', k.SARAS_ARM_PREFIXES)
def test_saras_arm_fk_matches_urdf(prefix, setups):
    tree = UrdfTree(urdf.saras_arm_urdf(prefix, setups[prefix.strip('/')]).to_string())
    names = k.saras_arm_joint_names(prefix)
    limits = k.saras_arm_joint_limits(prefix)
    assert list(limits) == names
    rng = np.random.default_rng(7)
    for _ in range(N):
        q = _random(limits, rng)
        values = dict(zip(names, q))
        base, tip = prefix + 'sbs_world', prefix + 'tool_tip'
        np.testing.assert_allclose(k.saras_arm_tip_in_base(q), tree.fk(base, tip, values), atol=TOL)
        np.testing.assert_allclose(k.saras_arm_rcm_in_base(q[:7]), tree.fk(base, prefix + 'rcm', values),
                                   atol=TOL)
        np.testing.assert_allclose(k.saras_arm_tip_in_rcm(q[7:]), tree.fk(prefix + 'rcm', tip, values),
                                   atol=TOL)


def test_saras_arm_fixed_pa_urdf_equals_setup_pose(setups):
    setup = setups['mesa_left']
    tree = UrdfTree(urdf.saras_arm_urdf_fixed_pa('mesa_left/', setup).to_string())
    np.testing.assert_allclose(tree.fk('mesa_left/sbs_world', 'mesa_left/rcm', {}),
                               k.saras_arm_rcm_in_base(setup.pa_joints), atol=TOL)


def test_pivot_closed_form_known_values():
    # Hand-derived: tip = insertion * (sin(yaw) cos(pitch), -sin(pitch), -cos(yaw) cos(pitch)).
    t = k.pivot_tip(math.radians(30), math.radians(20), 0.12)
    expected = 0.12 * np.array([0.5 * math.cos(math.radians(20)), -math.sin(math.radians(20)),
                                -math.sqrt(3) / 2 * math.cos(math.radians(20))])
    np.testing.assert_allclose(t[:3, 3], expected, atol=1e-15)
    np.testing.assert_allclose(t[:3, 2], expected / 0.12, atol=1e-15)  # z along the shaft, inward
    np.testing.assert_allclose(k.pivot_tip(0, 0, 0.1)[:3, 3], [0, 0, -0.1], atol=1e-15)


def test_saras_arm_rcm_invariant_shaft_line_passes_through_rcm(setups):
    """Whatever the ER joints, the instrument axis (from the URDF) passes through the RCM."""
    prefix = 'mesa_right/'
    tree = UrdfTree(urdf.saras_arm_urdf(prefix, setups['mesa_right']).to_string())
    names = k.saras_arm_joint_names(prefix)
    limits = k.saras_arm_joint_limits(prefix)
    rng = np.random.default_rng(3)
    q = np.concatenate([setups['mesa_right'].pa_joints, np.zeros(6)])
    rcm = tree.fk(prefix + 'sbs_world', prefix + 'rcm', dict(zip(names, q)))[:3, 3]
    for _ in range(N):
        q[7:] = _random(limits, rng)[7:]
        values = dict(zip(names, q))
        for link in ('instrument_link', 'tool_tip', 'er_insertion_link'):
            t = tree.fk(prefix + 'sbs_world', prefix + link, values)
            d = rcm - t[:3, 3]
            off_axis = d - (d @ t[:3, 2]) * t[:3, 2]
            assert np.linalg.norm(off_axis) < TOL
        # and the tip is er_insertion away from the RCM
        tip = tree.fk(prefix + 'sbs_world', prefix + 'tool_tip', values)[:3, 3]
        assert abs(np.linalg.norm(tip - rcm) - q[9]) < TOL


def test_saras_arm_ik_round_trip():
    limits = k.saras_arm_joint_limits()
    rng = np.random.default_rng(11)
    for _ in range(N):
        q = _random(limits, rng)[7:]
        q[2] = rng.uniform(0.01, 0.25)  # direction undefined at the RCM itself
        t = k.saras_arm_tip_in_rcm(q)
        er_roll = q[3]
        qi = k.saras_arm_ik_tip(t[:3, 3], roll=q[3] + q[4], er_roll=er_roll, jaw=q[5])
        np.testing.assert_allclose(qi[:3], q[:3], atol=TOL)
        np.testing.assert_allclose(k.saras_arm_tip_in_rcm(qi), t, atol=TOL)
        assert k.within_limits(np.concatenate([np.zeros(7), qi]), limits)


def test_saras_arm_ik_rejects_nan():
    with pytest.raises(ValueError):
        k.saras_arm_ik_tip([0.0, float('nan'), -0.1])
    with pytest.raises(ValueError):
        k.saras_arm_tip_in_base([0.0] * 11)


def test_psm_fk_matches_urdf_and_ik_round_trip():
    tree = UrdfTree(urdf.psm_urdf('PSM2').to_string())
    names = k.psm_joint_names()
    limits = k.psm_joint_limits()
    rng = np.random.default_rng(5)
    for _ in range(N):
        q = _random(limits, rng)
        np.testing.assert_allclose(k.psm_tip_in_base(q), tree.fk('PSM2', 'PSM2/tool_tip', dict(zip(names, q))),
                                   atol=TOL)
        q[2] = max(q[2], 0.01)
        q[4] = q[5] = 0.0  # straight wrist
        p = k.psm_tip_in_base(q)[:3, 3]
        np.testing.assert_allclose(k.psm_ik_position(p), q[:3], atol=TOL)
    # dVRK convention: tip at negative z when inserted
    np.testing.assert_allclose(k.psm_tip_in_base([0, 0, 0.1, 0, 0, 0])[:3, 3], [0, 0, -0.1], atol=1e-15)


def test_ecm_fk_and_cameras_match_urdf():
    hand_eye = cfg.load_hand_eye()
    tree = UrdfTree(urdf.ecm_urdf(hand_eye).to_string())
    names = k.ecm_joint_names()
    limits = k.ecm_joint_limits()
    rng = np.random.default_rng(9)
    for _ in range(N):
        q = _random(limits, rng)
        values = dict(zip(names, q))
        np.testing.assert_allclose(k.ecm_tip_in_base(q), tree.fk('ECM', 'ECM/tool_tip', values), atol=TOL)
        left, right = k.ecm_camera_poses(q, hand_eye)
        np.testing.assert_allclose(left, tree.fk('ECM', cfg.LEFT_OPTICAL, values), atol=TOL)
        np.testing.assert_allclose(right, tree.fk('ECM', cfg.RIGHT_OPTICAL, values), atol=TOL)
        # optical z = viewing direction = scope axis; baseline 5 mm along the left camera's x
        np.testing.assert_allclose(left[:3, 2], k.ecm_tip_in_base(q)[:3, 2], atol=TOL)
        np.testing.assert_allclose(np.linalg.inv(left) @ right[:, 3], [0.005, 0, 0, 1], atol=TOL)


def test_touch_fk_matches_urdf():
    prefix = 'touch_left/'
    tree = UrdfTree(urdf.touch_urdf(prefix).to_string())
    names = k.touch_joint_names(prefix)
    limits = k.touch_joint_limits(prefix)
    rng = np.random.default_rng(13)
    for _ in range(N):
        q = _random(limits, rng)
        t = k.touch_handle_in_base(q)
        np.testing.assert_allclose(t, tree.fk(prefix + 'base', prefix + 'handle', dict(zip(names, q))),
                                   atol=TOL)


def test_quaternion_helpers_against_rpy():
    rng = np.random.default_rng(17)
    for _ in range(N):
        rpy = rng.uniform(-3, 3, 3)
        r = rpy_to_matrix(rpy)
        np.testing.assert_allclose(quaternion_to_matrix(quaternion_from_matrix(r)), r, atol=1e-12)
