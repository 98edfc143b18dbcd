"""Cross-check with an independent renderer: saras_simulation's endoscope renderer (its
``endoscope_render`` command-line tool) draws the circular pattern (its own texture code, with lens
distortion and the tissue scene); our detector must recover the pose the simulator used, which also
pins down the shared pattern frame convention (z into the board, ArUco corner order)."""
import os
import subprocess

import cv2
import numpy as np
import pytest
import yaml

from saras_calibration.pattern import CircularPattern
from saras_common.transforms import inverse, rotation_angle_deg, transform_from_rpy

find_in_workspaces = pytest.importorskip('catkin.find_in_workspaces').find_in_workspaces
RENDER = (find_in_workspaces(['libexec'], project='saras_simulation', path='endoscope_render',
                             first_match_only=True) or [None])[0]
HERE = os.path.dirname(os.path.abspath(__file__))
LEFT_YAML = os.path.join(HERE, '..', '..', 'saras_simulation', 'config', 'endoscope_left.yaml')


def look_at(eye, target, up):
    """Optical frame at ``eye`` with z towards ``target`` and -y roughly along ``up``."""
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(-up, z)
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = eye
    return T


def scaled_camera(path, width, height):
    """K, D of the camera_calibration YAML scaled to width x height (pixel centres kept)."""
    with open(path) as f:
        info = yaml.safe_load(f)
    K = np.array(info['camera_matrix']['data'], float).reshape(3, 3)
    sx, sy = width / float(info['image_width']), height / float(info['image_height'])
    S = np.array([[sx, 0.0, 0.5 * sx - 0.5], [0.0, sy, 0.5 * sy - 0.5], [0.0, 0.0, 1.0]])
    return S @ K, np.array(info['distortion_coefficients']['data'], float)


@pytest.mark.skipif(RENDER is None, reason='saras_simulation endoscope_render not built')
def test_detect_pattern_rendered_by_endoscope_simulator(tmp_path):
    K, D = scaled_camera(LEFT_YAML, 640, 360)
    T_world_board = transform_from_rpy([-0.02, 0.0, 0.09], [np.pi, 0.0, 0.25])   # above the tissue
    pattern = CircularPattern()
    for k, (eye, up) in enumerate([([-0.02, 0.0, 0.30], [1.0, 0.0, 0.0]),
                                   ([0.03, 0.05, 0.28], [0.6, -0.8, 0.0]),
                                   ([-0.07, -0.03, 0.27], [0.0, 1.0, 0.3])]):
        T_world_cam = look_at(np.array(eye), T_world_board[:3, 3], np.array(up))
        q = cv2.Rodrigues(T_world_cam[:3, :3])[0].ravel()
        angle = np.linalg.norm(q)
        quat = np.r_[np.sin(angle / 2) * q / angle, np.cos(angle / 2)]
        out = str(tmp_path / ('frame%d.png' % k))
        subprocess.run([RENDER, '--camera-info', LEFT_YAML, '--width', '640', '--height', '360',
                        '--pose', ' '.join('%.12g' % v for v in np.r_[T_world_cam[:3, 3], quat]),
                        '--target', 'circles', '--target-pose', '-0.02 0 0.09 %.12g 0 0.25' % np.pi,
                        '--out', out], check=True, timeout=60)
        img = cv2.imread(out)
        T_cam_pattern, rms, ids = pattern.detect(img, K, D)
        truth = inverse(T_world_cam) @ T_world_board
        E = inverse(truth) @ T_cam_pattern
        assert len(ids) >= 3 and rms < 1.0, (k, ids, rms)
        assert rotation_angle_deg(E[:3, :3]) < 0.5, k
        # The simulator snaps marker corners to its 0.2 mm texels: allow 1 mm.
        assert np.linalg.norm(E[:3, 3]) < 0.001, (k, E[:3, 3])
