"""Core tests of saras_simulation.dvrk_motion (no roscore)."""
import os

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from saras_simulation import dvrk_motion as dm
from saras_common import transforms as tfm
from saras_description import frames as frames_yaml

CONFIG = os.path.join(os.path.dirname(__file__), '..', 'config', 'dvrk_sim.yaml')
FRAMES = os.path.join(os.path.dirname(__file__), '..', '..', 'saras_bringup', 'config',
                      'world_frames.yaml')


def test_quaternion_round_trip_matches_scipy():
    rng = np.random.default_rng(3)
    for _ in range(200):
        q = rng.standard_normal(4)
        q /= np.linalg.norm(q)
        R_ref = Rotation.from_quat(q).as_matrix()
        np.testing.assert_allclose(tfm.quaternion_to_matrix(q), R_ref, atol=1e-12)
        q2 = tfm.quaternion_from_matrix(R_ref)
        assert min(np.linalg.norm(q2 - q), np.linalg.norm(q2 + q)) < 1e-9
    R = tfm.rpy_to_matrix((0.1, -0.4, 2.0))
    np.testing.assert_allclose(R, Rotation.from_euler('xyz', [0.1, -0.4, 2.0]).as_matrix(), atol=1e-12)


def test_psm_ik_position_inverts_fk_with_a_straight_wrist():
    kin = dm.load_kinematics()
    rng = np.random.default_rng(0)
    for _ in range(100):
        p = rng.uniform([-0.1, -0.1, -0.2], [0.1, 0.1, -0.05])
        q = list(kin.psm_ik_position(p)) + [rng.uniform(-3, 3), 0.0, 0.0]
        T = kin.psm_tip_in_base(q)
        np.testing.assert_allclose(T[:3, 3], p, atol=1e-9)
        R = T[:3, :3]
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        # the shaft passes through the RCM: tip direction parallel to the position vector
        np.testing.assert_allclose(R[:, 2], p / np.linalg.norm(p), atol=1e-9)


def test_ecm_camera_frames_from_the_hand_eye():
    kin = dm.load_kinematics()
    # right eye +x of the left one in the optical frame (ROS stereo convention), 1-20 mm
    b = (tfm.inverse(kin.camera_in_tip('left')) @ kin.camera_in_tip('right'))[:3, 3]
    assert 0.001 <= b[0] <= 0.02 and abs(b[1]) < 1e-6 and abs(b[2]) < 1e-6


def test_suturing_motion_is_continuous_and_dips():
    m = dm.SuturingMotion(centre=[-0.08, 0.05, -0.125], drive_dir=[0, 1, 0], wound_dir=[1, 0, 0],
                          arc_radius=0.012, lift=0.025, period=8.0, stitches=4)
    ts = np.arange(0.0, 40.0, 0.001)
    pts = np.array([m.wrist_point(t)[0] for t in ts])
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    # continuous, max speed < 0.05 m/s (no jump anywhere, also at stitch changes and wrap-around)
    assert steps.max() < 0.05 * 0.001
    assert pts[:, 2].min() == pytest.approx(-0.125 - 0.012, abs=1e-4)
    assert pts[:, 2].max() == pytest.approx(-0.125 + 0.025, abs=1e-4)


def test_suturing_stitches_go_back_and_forth_along_the_wound():
    m = dm.SuturingMotion(centre=[0, 0, -0.12], wound_dir=[1, 0, 0], period=8.0, stitches=4,
                          stitch_spacing=0.006)
    xs = [m.wrist_point(8.0 * k + 1.0)[0][0] for k in range(8)]
    np.testing.assert_allclose(xs, np.array([-1.5, -0.5, 0.5, 1.5, 0.5, -0.5, -1.5, -0.5]) * 0.006
                               + m.wrist_point(1.0)[0][0] + 0.009, atol=1e-12)


def test_ecm_dwells_then_moves():
    e = dm.EcmMotion([{'look_at': [-0.13, 0, -0.17], 'insertion': 0.09},
                      {'look_at': [-0.12, 0.03, -0.17], 'insertion': 0.085}], dwell=5.0, move_time=2.0)
    q0 = e.joints(0.0)
    assert e.joints(4.99) == q0
    mid = e.joints(6.0)
    end = e.joints(7.0)
    assert mid != q0 and end != q0
    yaw, pitch = dm.direction_to_yaw_pitch([-0.12, 0.03, -0.17])
    np.testing.assert_allclose(end, [yaw, pitch, 0.085, 0.0], atol=1e-12)
    # back to the first viewpoint after the second dwell + move
    np.testing.assert_allclose(e.joints(14.0), q0, atol=1e-12)


def test_shipped_config_puts_tips_in_contract_workspace():
    with open(CONFIG) as f:
        cfg = yaml.safe_load(f)
    kin = dm.load_kinematics()
    core = dm.DvrkSimCore.from_config(cfg, kinematics=kin)
    frames = frames_yaml.frames_by_child(frames_yaml.load_frames(FRAMES, root=None))
    for t in np.arange(0.0, 60.0, 0.37):
        s = core.sample(t)
        assert set(s) == {'PSM1', 'PSM2', 'ECM'}
        for arm in ('PSM1', 'PSM2'):
            q, T = s[arm]
            assert len(q) == len(dm.PSM_JOINT_NAMES)
            r = np.linalg.norm(T[:3, 3])
            assert 0.10 <= r <= 0.18, (arm, t, r)     # 10-18 cm below the RCM
            assert T[2, 3] < 0
            tip_w = frames[arm][1] @ np.append(T[:3, 3], 1.0)
            assert np.linalg.norm(tip_w[:2] - [0.02, 0.0]) < 0.065  # near the surgical site (PSM1 stitches beside the right iliac wing)
        q, T = s['ECM']
        assert len(q) == len(dm.ECM_JOINT_NAMES)
        assert T[2, 3] < 0


def test_bad_config_names_parameter():
    with pytest.raises(ValueError, match='psm/PSM1'):
        dm.DvrkSimCore.from_config({'psm': {'PSM1': {'centre': [0, 'x', 0]}}},
                                   kinematics=dm.load_kinematics())
    with pytest.raises(ValueError, match='ecm'):
        dm.DvrkSimCore.from_config({'ecm': {'viewpoints': [{'look_at': [0, 0, -1], 'insertion': 5}]}},
                                   kinematics=dm.load_kinematics())


def test_replay_schedule_plays_each_record_once_and_loops():
    recs = [(10.0 + 0.01 * i, 'k', i) for i in range(100)]
    sch = dm.ReplaySchedule(recs, loop=True)
    got = []
    for k in range(1, 250):
        got.extend(r[2] for r in sch.due(k * 0.01 + 1e-9))
    assert got[:100] == list(range(100))
    assert got[100:200] == list(range(100))   # second pass identical
    sch2 = dm.ReplaySchedule(recs, loop=False)
    assert [r[2] for r in sch2.due(5.0)] == list(range(100))
    assert sch2.finished and sch2.due(6.0) == []
    with pytest.raises(ValueError):
        dm.ReplaySchedule([])


def test_sample_grid_catches_up_with_grid_times():
    """SampleGrid: every grid time once, at the grid time, however the wake-ups jitter; a late
    wake-up returns the missed samples at once (<= max_catch_up); beyond that the grid restarts
    and counts what it skipped; a clock jump back restarts it."""
    from saras_simulation.dvrk_motion import SampleGrid
    g = SampleGrid(0.01, max_catch_up=5)
    out = []
    for now in (0.0, 0.0101, 0.0199, 0.0305, 0.07):      # 0.07: 4 samples late
        out += g.due(now)
    assert np.allclose(out, [0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07])
    assert g.missed == 0
    assert g.due(0.0705) == []
    late = g.due(0.2)                                    # 13 samples due: 5 now, 8 skipped
    assert np.allclose(late, [0.08, 0.09, 0.10, 0.11, 0.12]) and g.missed == 8
    assert np.allclose(g.due(0.215), [0.21])             # grid restarted after now
    assert np.allclose(g.due(0.1), [0.1])                # clock jumped back: restart there
    ts = []
    g = SampleGrid(0.01, 10)
    for now in np.arange(0.0, 5.0, 0.0137):              # wake-ups off the grid
        ts += g.due(float(now))
    assert np.allclose(np.diff(ts), 0.01) and len(ts) == int(round(ts[-1] / 0.01)) + 1
    for bad in ((0.0, 5), (float('nan'), 5), (0.01, 0), (0.01, True), (0.01, 2.5)):
        with pytest.raises(ValueError):
            SampleGrid(*bad)
