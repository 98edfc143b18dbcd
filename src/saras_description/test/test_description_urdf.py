"""Generated URDFs: check_urdf, names, limits, placement of the RCMs in the world, CLI."""
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
from saras_description_testlib import UrdfTree

from saras_description import config as cfg
from saras_description import kinematics as k
from saras_description import urdf
from saras_common.transforms import transform_from_rpy

PKG = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
MAKE_URDF = os.path.join(PKG, 'scripts', 'make_urdf')
CASES = [
    ['saras_arm', '--prefix', 'mesa_left/'],
    ['saras_arm', '--prefix', 'mesa_right/'],
    ['saras_arm', '--prefix', 'mesa_right/', '--fixed-pa'],
    ['psm', '--prefix', 'PSM1'],
    ['psm', '--prefix', 'PSM2'],
    ['ecm'],
    ['touch', '--prefix', 'touch_left/'],
    ['touch', '--prefix', 'touch_right/'],
    ['platform'],
]
ROOTS = {'saras_arm': None, 'psm': None, 'ecm': 'ECM', 'touch': None, 'platform': 'world'}


def _env():
    env = dict(os.environ)
    env['PYTHONPATH'] = os.path.join(PKG, 'src') + os.pathsep + env.get('PYTHONPATH', '')
    return env


def _make_urdf(args):
    return subprocess.run([sys.executable, MAKE_URDF] + args, env=_env(), capture_output=True,
                          text=True, timeout=60, check=False)


@pytest.mark.parametrize('args', CASES, ids=['_'.join(c).replace('/', '') for c in CASES])
def test_check_urdf_passes(args, tmp_path):
    assert shutil.which('check_urdf'), 'check_urdf missing: apt-get install liburdfdom-tools'
    out = _make_urdf(args)
    assert out.returncode == 0, out.stderr
    path = tmp_path / 'robot.urdf'
    path.write_text(out.stdout)
    check = subprocess.run(['check_urdf', str(path)], capture_output=True, text=True, timeout=30,
                           check=False)
    assert check.returncode == 0, check.stdout + check.stderr
    assert 'Successfully Parsed XML' in check.stdout
    prefix = args[2] if len(args) > 2 else ''
    root = {'saras_arm': prefix + 'sbs_world', 'psm': prefix, 'ecm': 'ECM',
            'touch': prefix + 'base', 'platform': 'world'}[args[0]]
    assert 'root Link: %s ' % root in check.stdout


def test_joint_names_and_limits_in_urdf_match_kinematics():
    setups = cfg.load_saras_arms()
    cases = [(urdf.saras_arm_urdf('mesa_left/', setups['mesa_left']), k.saras_arm_joint_limits('mesa_left/')),
             (urdf.psm_urdf('PSM1'), k.psm_joint_limits()),
             (urdf.ecm_urdf(), k.ecm_joint_limits()),
             (urdf.touch_urdf('touch_right/'), k.touch_joint_limits('touch_right/'))]
    for robot, limits in cases:
        tree = UrdfTree(robot.to_string())
        movable = {j['name']: j for j in tree.joints.values() if j['type'] != 'fixed'}
        assert set(movable) == set(limits)
        for name, lim in limits.items():
            elem = movable[name]['limit']
            assert movable[name]['type'] == lim.kind
            assert float(elem.get('lower')) == pytest.approx(lim.lower, abs=1e-11)
            assert float(elem.get('upper')) == pytest.approx(lim.upper, abs=1e-11)
            assert lim.lower < lim.upper


def test_required_frames_exist():
    links = set(UrdfTree(urdf.platform_urdf().to_string()).links)
    for side in ('mesa_left/', 'mesa_right/'):
        for name in ('sbs_world', 'flange', 'rcm', 'instrument_link', 'jaw_link', 'tool_tip'):
            assert side + name in links
    for arm in ('PSM1', 'PSM2', 'ECM'):
        assert arm in links and arm + '/tool_tip' in links
    assert {'endoscope/left_optical_frame', 'endoscope/right_optical_frame', 'console',
            'touch_left/handle', 'touch_right/handle', 'bones_marker_frame'} <= links


@pytest.mark.parametrize('side', ['mesa_left', 'mesa_right'])
def test_setup_pose_puts_rcm_on_the_trocar(side):
    """world_frames.yaml placement x PA set-up pose = documented trocar; shaft points at site."""
    import yaml  # pylint: disable=import-outside-toplevel
    frames = {f.child: f for f in cfg.load_frames(cfg.default_world_frames_path())}
    base = frames[side + '/sbs_world']
    setup = cfg.load_saras_arms()[side]
    with open(cfg.default_path('saras_arms.yaml')) as f:
        arm = yaml.safe_load(f)['arms'][side]
    expected = {'mesa_left': [0.02, 0.13, 0.20], 'mesa_right': [0.02, -0.13, 0.20]}[side]
    assert arm['rcm_world'] == pytest.approx(expected)  # docs/interfaces.md
    # chain through the URDF (independent FK) in the complete platform description
    tree = UrdfTree(urdf.platform_urdf().to_string())
    values = dict(zip(k.saras_arm_pa_joint_names(side + '/'), setup.pa_joints))
    rcm = tree.fk('world', side + '/rcm', values)
    np.testing.assert_allclose(rcm[:3, 3], expected, atol=1e-6)
    np.testing.assert_allclose(transform_from_rpy(base.xyz, base.rpy) @ k.saras_arm_rcm_in_base(setup.pa_joints),
                               rcm, atol=1e-9)
    site = np.array([0.0, 0.0, 0.10])
    direction = (site - rcm[:3, 3]) / np.linalg.norm(site - rcm[:3, 3])
    np.testing.assert_allclose(-rcm[:3, 2], direction, atol=1e-6)  # tip at -z goes to the site
    # With ER joints at zero and 13 cm insertion the tip is in the abdomen, below the trocar.
    tip = rcm @ k.saras_arm_tip_in_rcm([0, 0, 0.13, 0, 0])
    assert tip[2, 3] < rcm[2, 3] - 0.05
    assert k.within_limits(setup.pa_joints, dict(list(k.saras_arm_joint_limits().items())[:7]))


def test_make_urdf_bad_arguments_exit_2_with_message(tmp_path):
    out = _make_urdf(['saras_arm', '--prefix', 'mesa_middle/'])
    assert out.returncode == 2 and 'mesa_middle' in out.stderr and not out.stdout
    out = _make_urdf(['saras_arm', '--prefix', 'mesa_left'])
    assert out.returncode == 2 and 'must end with' in out.stderr
    bad = tmp_path / 'hand_eye.yaml'
    bad.write_text('frames:\n  - {parent: ECM/tool_tip, child: endoscope/left_optical_frame, '
                   'xyz: [0, 0, .nan], rpy: [0, 0, 0]}\n')
    out = _make_urdf(['ecm', '--config', str(bad)])
    assert out.returncode == 2 and '"xyz" must be finite' in out.stderr
    # roslaunch's private arguments are ignored
    out = _make_urdf(['touch', '--prefix', 'touch_left/', '__name:=x', '__log:=/tmp/x.log'])
    assert out.returncode == 0 and '<robot name="touch_left">' in out.stdout


def test_rviz_config_matches_the_descriptions():
    """platform.rviz: a RobotModel per robot_description, the contract topics, every URDF link
    listed in the TF display (unlisted frames would be shown with names), fixed frame world."""
    import yaml  # pylint: disable=import-outside-toplevel
    with open(os.path.join(PKG, 'rviz', 'platform.rviz')) as f:
        rviz = yaml.safe_load(f)
    manager = rviz['Visualization Manager']
    assert manager['Global Options']['Fixed Frame'] == 'world'
    displays = manager['Displays']
    models = {d['Robot Description'] for d in displays if d['Class'] == 'rviz/RobotModel'}
    assert models == {r + '/robot_description' for r in
                      ('mesa_left', 'mesa_right', 'PSM1', 'PSM2', 'ECM', 'touch_left', 'touch_right')}
    by_class = {d['Class']: d for d in displays}
    assert by_class['rviz/MarkerArray']['Marker Topic'] == '/collision/markers'
    assert by_class['rviz/Image']['Image Topic'] == '/visual_feedback/left/image'
    frames = by_class['rviz/TF']['Frames']
    assert by_class['rviz/TF']['Show Names'] is True
    links = set(UrdfTree(urdf.platform_urdf().to_string()).links)
    assert links - set(frames) == set()
    shown = {name for name, v in frames.items() if isinstance(v, dict) and v['Value']}
    assert {'world', 'mesa_left/rcm', 'mesa_right/tool_tip', 'PSM1/tool_tip', 'ECM/tool_tip',
            'touch_left/stylus'} <= shown
