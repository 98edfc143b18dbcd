"""Full calibration pipeline at core level, with the platform kinematics (saras_description).

Ground truth: the simulation world frames (saras_bringup/config/world_frames.yaml) and a
pattern on the table. Simulated procedure: hand-eye from 20 noisy samples, the arms touch the
dots (inverse + forward kinematics, 0.2 mm touch noise), the endoscope sees the rendered
pattern. Check (issue 8): a PSM tool tip and a SARAS tool tip placed at the same world point
agree within 1 mm after calibration.
"""
import os

import numpy as np
import pytest

from saras_calibration.global_registration import GlobalRegistration
from saras_calibration.hand_eye import solve_hand_eye
from saras_calibration.pattern import CircularPattern
from saras_calibration.synthetic import perturb_pose
from saras_common.transforms import (inverse, make_transform, rotation_angle_deg, transform_from_rpy,
                                     transform_points)
from saras_calibration.world_frames import entry_transform, load_world_frames, save_world_frames

kin = pytest.importorskip('saras_description.kinematics')
setup_pose = pytest.importorskip('saras_description.setup_pose')

HERE = os.path.dirname(os.path.abspath(__file__))
WORLD_FRAMES = os.path.join(HERE, '..', '..', 'saras_bringup', 'config', 'world_frames.yaml')
TOUCH_NOISE = 0.0002   # [m] per axis


@pytest.fixture(scope='module')
def scene():
    truth = {e['child']: entry_transform(e) for e in load_world_frames(WORLD_FRAMES) if e['parent'] == 'world'}
    rng = np.random.default_rng(42)
    # Pattern printed side up on the table near the surgical site, rotated 0.2 rad about z.
    T_world_pattern = transform_from_rpy([0.05, 0.0, 0.07], [np.pi, 0.0, 0.2])
    pa = {}
    for arm, rcm in (('mesa_left', [0.02, 0.13, 0.20]), ('mesa_right', [0.02, -0.13, 0.20])):
        r, d = setup_pose.rcm_targets_in_base(truth[arm + '/sbs_world'], np.array(rcm), np.array([0.0, 0.0, 0.10]))
        pa[arm] = setup_pose.solve_pa_setup(r, d, iterations=200)[0]
    return truth, T_world_pattern, pa, rng


def psm_tip(point_in_base):
    return kin.psm_tip_in_base(np.concatenate([kin.psm_ik_position(point_in_base), [0.3, 0.0, 0.0]]))[:3, 3]


def saras_tip(q_pa, point_in_base):
    rcm = kin.saras_arm_rcm_in_base(q_pa)
    er = kin.saras_arm_ik_tip(transform_points(inverse(rcm), point_in_base)[0], roll=0.2)
    return kin.saras_arm_tip_in_base(np.concatenate([q_pa, er]))[:3, 3]


def test_full_pipeline(scene, tmp_path):
    truth, T_wp, pa, rng = scene
    pattern = CircularPattern()
    dots_world = transform_points(T_wp, pattern.dot_positions())
    reg = GlobalRegistration(pattern, T_world_pattern=T_wp)

    # 1. Arms touch every dot: IK to the dot in the true base, FK gives the reported tip.
    for base in ('PSM1', 'PSM2'):
        for k, p in enumerate(transform_points(inverse(truth[base]), dots_world)):
            reg.add_touch(base, k, psm_tip(p) + rng.normal(0, TOUCH_NOISE, 3))
    for arm in ('mesa_left', 'mesa_right'):
        base = arm + '/sbs_world'
        for k, p in enumerate(transform_points(inverse(truth[base]), dots_world)):
            reg.add_touch(base, k, saras_tip(pa[arm], p) + rng.normal(0, TOUCH_NOISE, 3))

    # 2. Hand-eye of the ECM: 20 samples, 0.1 deg / 0.5 mm noise, 3 bad marker poses.
    X_true = transform_from_rpy([-0.0025, 0.0, 0.0], [0.0, np.radians(30), 0.0])   # 30 deg scope
    T_ecm_pattern = inverse(truth['ECM']) @ T_wp
    ee, cm = [], []
    while len(ee) < 20:
        q = [rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), rng.uniform(0.05, 0.10), rng.uniform(-1.0, 1.0)]
        T_be = kin.ecm_tip_in_base(q)
        T_cm = inverse(X_true) @ inverse(T_be) @ T_ecm_pattern
        ee.append(perturb_pose(T_be, rng, np.radians(0.1) / np.sqrt(3), 0.0005 / np.sqrt(3)))
        cm.append(perturb_pose(T_cm, rng, np.radians(0.1) / np.sqrt(3), 0.0005 / np.sqrt(3)))
    for i in (3, 9, 15):
        cm[i] = cm[i] @ transform_from_rpy([0.03, 0.0, 0.0], [0.4, 0.0, 0.0])
    he = solve_hand_eye(ee, cm)
    assert [i for i, ok in enumerate(he.inliers) if not ok] == [3, 9, 15]

    # 3. The endoscope looks at the pattern from the ECM home pose: detect in a rendered image.
    K = np.array([[900.0, 0.0, 639.5], [0.0, 900.0, 359.5], [0.0, 0.0, 1.0]])
    centre = T_ecm_pattern[:3, 3]

    def off_axis(q):   # angle between the optical axis and the pattern centre
        T = kin.ecm_tip_in_base(q) @ X_true
        d = centre - T[:3, 3]
        return np.arccos(T[:3, 2] @ d / np.linalg.norm(d))
    q_view = min(([y, p, 0.04, 0.0] for y in np.linspace(-0.8, 0.8, 33) for p in np.linspace(-0.8, 0.8, 33)),
                 key=off_axis)
    T_be = kin.ecm_tip_in_base(q_view)
    T_cam_pattern_true = inverse(T_be @ X_true) @ T_ecm_pattern
    img = pattern.render(K, (1280, 720), T_cam_pattern_true)
    T_cam_pattern, px_rms, ids = pattern.detect(img, K, np.zeros(5))
    assert len(ids) >= 3 and px_rms < 1.0
    reg.add_endoscope_view('ECM', T_be, he.transform, T_cam_pattern)

    # 4. World frames written in the platform format and read back.
    out = tmp_path / 'world_frames.yaml'
    save_world_frames(str(out), reg.entries())
    cal = {e['child']: entry_transform(e) for e in load_world_frames(str(out))}
    assert set(cal) == {'PSM1', 'PSM2', 'mesa_left/sbs_world', 'mesa_right/sbs_world', 'ECM'}

    # 5. The check: tips placed at the same world point agree within 1 mm.
    worst = 0.0
    for p in rng.uniform([-0.04, -0.04, 0.06], [0.06, 0.04, 0.12], (50, 3)):
        tips = {}
        for base in ('PSM1', 'PSM2'):
            tips[base] = transform_points(cal[base], psm_tip(transform_points(inverse(truth[base]), p)[0]))[0]
        for arm in ('mesa_left', 'mesa_right'):
            base = arm + '/sbs_world'
            tip = saras_tip(pa[arm], transform_points(inverse(truth[base]), p)[0])
            tips[base] = transform_points(cal[base], tip)[0]
        for a in ('PSM1', 'PSM2'):
            for b in ('mesa_left/sbs_world', 'mesa_right/sbs_world'):
                worst = max(worst, np.linalg.norm(tips[a] - tips[b]))
    assert worst < 0.001, worst
    # Every base agrees with the ground truth; the endoscope within its (looser) error budget.
    for base in ('PSM1', 'PSM2', 'mesa_left/sbs_world', 'mesa_right/sbs_world'):
        assert np.linalg.norm(cal[base][:3, 3] - truth[base][:3, 3]) < 0.001
        assert rotation_angle_deg(cal[base][:3, :3].T @ truth[base][:3, :3]) < 0.5
    E = inverse(truth['ECM']) @ cal['ECM']
    site = transform_points(inverse(truth['ECM']), [0.0, 0.0, 0.10])[0]
    assert np.linalg.norm(transform_points(E, site)[0] - site) < 0.003
