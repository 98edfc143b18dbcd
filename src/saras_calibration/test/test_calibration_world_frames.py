"""World-frame YAML round trip and validation."""
import os

import numpy as np
import pytest

from saras_common.transforms import inverse, transform_from_rpy
from saras_calibration.world_frames import (WorldFramesError, entry_transform, frame_entry, load_world_frames,
                                            merge_frames, registration_frames, save_world_frames)

BRINGUP = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'saras_bringup', 'config',
                       'world_frames.yaml')


def test_round_trip(tmp_path):
    T = transform_from_rpy([0.1, -0.08, 0.22], [0.1, -0.2, 2.5])
    p = tmp_path / 'sub' / 'wf.yaml'
    save_world_frames(str(p), [frame_entry('world', 'PSM1', T)], comment='test')
    e = load_world_frames(str(p))
    assert e[0]['parent'] == 'world' and e[0]['child'] == 'PSM1'
    np.testing.assert_allclose(entry_transform(e[0]), T, atol=1e-7)


@pytest.mark.skipif(not os.path.exists(BRINGUP), reason='saras_bringup not present')
def test_reads_platform_file_and_merges():
    template = load_world_frames(BRINGUP)
    T_bp = transform_from_rpy([0.0, 0.0, -0.15], [np.pi, 0, 0])
    upd = registration_frames({'PSM1': T_bp, 'newbase': T_bp})
    merged = merge_frames(template, upd)
    assert [e['child'] for e in merged[:len(template)]] == [e['child'] for e in template]
    assert merged[-1]['child'] == 'newbase'
    psm1 = [e for e in merged if e['child'] == 'PSM1'][0]
    np.testing.assert_allclose(entry_transform(psm1), inverse(T_bp), atol=1e-7)


def test_bad_files(tmp_path):
    p = tmp_path / 'bad.yaml'
    p.write_text('frames:\n  - {parent: world, child: PSM1, xyz: [0, 0], rpy: [0, 0, 0]}\n')
    with pytest.raises(WorldFramesError, match='xyz'):
        load_world_frames(str(p))
    p.write_text('frames: {a: 1}\n')
    with pytest.raises(WorldFramesError, match='frames'):
        load_world_frames(str(p))
    p.write_text(':::')
    with pytest.raises(WorldFramesError):
        load_world_frames(str(p))
    with pytest.raises(WorldFramesError, match='cannot read'):
        load_world_frames(str(tmp_path / 'missing.yaml'))


def test_hand_eye_file_loads_in_saras_description(tmp_path):
    """The hand-eye file we write is the one the ECM URDF generator reads."""
    config = pytest.importorskip('saras_description.config')
    X = transform_from_rpy([-0.002, 0.001, 0.004], [0.01, 0.52, -0.02])
    T_lr = transform_from_rpy([0.005, 0.0, 0.0001], [0.0, -0.003, 0.0])
    p = tmp_path / 'ecm_hand_eye.yaml'
    save_world_frames(str(p), [frame_entry('ECM/tool_tip', 'endoscope/left_optical_frame', X),
                               frame_entry('endoscope/left_optical_frame', 'endoscope/right_optical_frame', T_lr)])
    he = config.load_hand_eye(str(p))
    np.testing.assert_allclose(he.tip_to_left, X, atol=1e-6)
    np.testing.assert_allclose(he.left_to_right, T_lr, atol=1e-6)
