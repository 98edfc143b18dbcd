"""saras_description.frames: THE parser of the frames-YAML format (validation, composition)."""
import math
import os

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from saras_description.frames import FramesError, load_frames, parse_frames, world_transform

HERE = os.path.dirname(os.path.abspath(__file__))
SHIPPED = os.path.join(HERE, "..", "..", "saras_bringup", "config", "world_frames.yaml")


def test_shipped_file_is_valid_and_places_the_scene():
    frames = load_frames(SHIPPED)
    children = {f.child for f in frames}
    for needed in ('PSM1', 'PSM2', 'ECM', 'mesa_left/sbs_world', 'mesa_right/sbs_world',
                   'bones_marker_frame', 'touch_left/base', 'touch_right/base'):
        assert needed in children
    T = world_transform(frames, 'touch_left/base')
    assert np.allclose(T[:3, 3], [-1.2, 0.20, 0.8])
    # the left SARAS base is rotated -90 deg about z: its x axis points along world -y (to the table)
    Tl = world_transform(frames, 'mesa_left/sbs_world')
    assert np.allclose(Tl[:3, 0], [0, -1, 0], atol=1e-12)


def entry(**kw):
    base = {'parent': 'world', 'child': 'a', 'xyz': [0, 0, 0], 'rpy': [0, 0, 0]}
    base.update(kw)
    return base


@pytest.mark.parametrize('bad, message', [
    ({'frames': [entry(xyz=[0, 0])]}, '"xyz" must be a list of 3'),
    ({'frames': [entry(xyz=[0, 'x', 0])]}, 'non-numeric'),
    ({'frames': [entry(rpy=[0, float('nan'), 0])]}, 'finite'),
    ({'frames': [entry(child='')]}, '"child" must be a non-empty'),
    ({'frames': [entry(child='/a')]}, 'leading slash'),
    ({'frames': [entry(), entry()]}, 'already has parent'),
    ({'frames': [entry(parent='b', child='a'), entry(parent='a', child='b')]}, 'cycle'),
    ({'frames': [entry(parent='nowhere')]}, 'not connected'),
    ({'frames': [{'parent': 'world', 'child': 'a', 'xyz': [0, 0, 0], 'quaternion': [0, 0, 0, 2]}]}, 'norm'),
    ({'nothing': 1}, '"frames" list'),
])
def test_invalid_files_are_rejected_with_a_clear_message(bad, message):
    with pytest.raises(FramesError, match=message):
        parse_frames(bad)


def test_chain_composition():
    frames = parse_frames({'frames': [
        entry(child='a', xyz=[1, 0, 0], rpy=[0, 0, math.pi / 2]),
        entry(parent='a', child='b', xyz=[1, 0, 0])]})
    T = world_transform(frames, 'b')
    assert np.allclose(T[:3, 3], [1, 1, 0])


def test_unreadable_file(tmp_path):
    p = tmp_path / 'f.yaml'
    p.write_text('frames: [ {parent: world')
    with pytest.raises(FramesError, match='cannot read'):
        load_frames(str(p))


def test_rpy_kept_as_written_and_derived_from_quaternions():
    frames = parse_frames({'frames': [
        entry(child='a', rpy=[0.1, -0.2, 0.3]),
        {'parent': 'a', 'child': 'b', 'xyz': [1, 2, 3], 'quaternion': list(Rotation.from_euler('xyz', [0.3, 0.2, -0.1]).as_quat())}]})
    assert frames[0].rpy == (0.1, -0.2, 0.3)
    assert np.allclose(frames[1].rpy, [0.3, 0.2, -0.1], atol=1e-12)
    assert frames[1].xyz == (1.0, 2.0, 3.0)


def test_forest_without_root():
    data = {'frames': [entry(parent='ECM/tool_tip', child='cam'), entry(parent='cam', child='right')]}
    with pytest.raises(FramesError, match='not connected'):
        parse_frames(data)
    frames = parse_frames(data, root=None)
    assert [f.child for f in frames] == ['cam', 'right']
    cyc = {'frames': [entry(parent='b', child='a'), entry(parent='a', child='b')]}
    with pytest.raises(FramesError, match='cycle'):
        parse_frames(cyc, root=None)
