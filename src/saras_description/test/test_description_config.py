"""Validation of the YAML configuration files: clear errors naming the offending key."""
import numpy as np
import pytest

from saras_description import config as cfg
from saras_description import urdf
from saras_common.transforms import transform_from_rpy


def _write(tmp_path, text, name='c.yaml'):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_default_files_load():
    setups = cfg.load_saras_arms()
    assert set(setups) == {'mesa_left', 'mesa_right'}
    assert setups['mesa_left'].shaft_diameter == pytest.approx(0.005)
    # the two set-up poses are mirror images (bases and trocars are mirrored about the xz-plane)
    np.testing.assert_allclose(setups['mesa_left'].pa_joints[[1, 3, 5]],
                               setups['mesa_right'].pa_joints[[1, 3, 5]], atol=1e-6)
    np.testing.assert_allclose(setups['mesa_left'].pa_joints[[0, 2, 4, 6]],
                               -setups['mesa_right'].pa_joints[[0, 2, 4, 6]], atol=1e-6)
    he = cfg.load_hand_eye()
    np.testing.assert_allclose(he.left_to_right, transform_from_rpy([0.005, 0, 0], [0, 0, 0]))


@pytest.mark.parametrize('text, needle', [
    ('arms: {mesa_left: {pa_joints: [0, 0, 0]}}', 'pa_joints'),
    ('arms: {mesa_left: {pa_joints: [0, 0, 0, 4.0, 0, 0, 0]}}', 'pa_joint_4'),
    ('arms: {mesa_left: {pa_joints: [0, 0, 0, 0, 0, 0, .nan]}}', 'non-finite'),
    ('arms: {mesa_left: {pa_joints: [0, 0, 0, 0, 0, 0, 0], shaft_diameter: 0.05}}', 'shaft_diameter'),
    ('arms: []', '"arms"'),
    ('- just a list', 'mapping'),
    ('arms: {mesa_left: {pa_joints: [0, 0, a, 0, 0, 0, 0]}}', 'numbers'),
])
def test_saras_arms_errors(tmp_path, text, needle):
    with pytest.raises(cfg.ConfigError) as err:
        cfg.load_saras_arms(_write(tmp_path, text))
    assert needle in str(err.value)


@pytest.mark.parametrize('text, needle', [
    ('frames: [{parent: ECM/tool_tip, child: endoscope/left_optical_frame, xyz: [0, 0, 0], rpy: [0, 0, 0]}]',
     'right_optical_frame'),
    ('frames:\n - {parent: ECM/tool_tip, child: endoscope/left_optical_frame, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n'
     ' - {parent: endoscope/left_optical_frame, child: endoscope/right_optical_frame, xyz: [0.5, 0, 0],'
     ' rpy: [0, 0, 0]}', 'baseline'),
    ('frames: [{parent: ECM/tool_tip, xyz: [0, 0, 0], rpy: [0, 0, 0]}]', 'child'),
    ('frames: [{parent: a, child: b, xyz: [0, 0], rpy: [0, 0, 0]}]', 'xyz'),
])
def test_hand_eye_errors(tmp_path, text, needle):
    with pytest.raises(cfg.ConfigError) as err:
        cfg.load_hand_eye(_write(tmp_path, text))
    assert needle in str(err.value)


def test_missing_file_is_a_config_error(tmp_path):
    with pytest.raises(cfg.ConfigError) as err:
        cfg.load_frames(str(tmp_path / 'nope.yaml'))
    assert 'nope.yaml' in str(err.value)


def test_calibrated_hand_eye_reaches_the_urdf(tmp_path):
    path = _write(tmp_path, 'frames:\n'
                  ' - {parent: ECM/tool_tip, child: endoscope/left_optical_frame, xyz: [0.001, 0.002, 0.003],'
                  ' rpy: [0.01, 0.02, 1.5]}\n'
                  ' - {parent: endoscope/left_optical_frame, child: endoscope/right_optical_frame,'
                  ' xyz: [0.0051, 0.0001, 0], rpy: [0, 0.003, 0]}\n')
    text = urdf.ecm_urdf(cfg.load_hand_eye(path)).to_string()
    assert 'xyz="0.001 0.002 0.003" rpy="0.01 0.02 1.5"' in text
    assert 'xyz="0.0051 0.0001 0.0" rpy="0.0 0.003 0.0"' in text


def test_platform_requires_every_robot_root_in_world_frames(tmp_path):
    path = _write(tmp_path, 'frames: [{parent: world, child: PSM1, xyz: [0, 0, 0], rpy: [0, 0, 0]}]')
    with pytest.raises(cfg.ConfigError) as err:
        urdf.platform_urdf(path)
    assert 'sbs_world' in str(err.value)


def test_demo_motion_within_limits_and_tips_near_site():
    from saras_description import kinematics as k  # pylint: disable=import-outside-toplevel
    from saras_description.demo_motion import DemoMotion  # pylint: disable=import-outside-toplevel
    motion = DemoMotion(cfg.load_saras_arms())
    limits = {'/mesa_left/joint_states': k.saras_arm_joint_limits('mesa_left/'),
              '/mesa_right/joint_states': k.saras_arm_joint_limits('mesa_right/'),
              '/dvrk/PSM1/state_joint_current': k.psm_joint_limits(),
              '/dvrk/PSM2/state_joint_current': k.psm_joint_limits(),
              '/dvrk/ECM/state_joint_current': k.ecm_joint_limits(),
              '/touch_left/joint_states': k.touch_joint_limits('touch_left/'),
              '/touch_right/joint_states': k.touch_joint_limits('touch_right/')}
    for t in np.linspace(0.0, 60.0, 121):
        states = motion.joint_states(t)
        assert {s[0] for s in states} == set(limits)
        for topic, names, q in states:
            assert names == list(limits[topic])
            assert k.within_limits(q, limits[topic])
    rest = {s[0]: s[2] for s in motion.joint_states(0.0, animate=False)}
    # PSM1 at world (0.10, -0.08, 0.22), world-aligned: tip at the site region (0.02, -0.02, 0.10)
    tip = k.psm_tip_in_base(rest['/dvrk/PSM1/state_joint_current'])[:3, 3] + [0.10, -0.08, 0.22]
    np.testing.assert_allclose(tip, [0.02, -0.02, 0.10], atol=1e-9)
