"""Cross-check with an independent renderer: saras_drivers' endoscope simulator draws the
circular pattern (its own texture code, with lens distortion and the tissue scene); our
detector must recover the pose the simulator used, which also pins down the shared pattern
frame convention (z into the board, ArUco corner order)."""
import os

import numpy as np
import pytest

from saras_calibration.pattern import CircularPattern
from saras_common.transforms import inverse, rotation_angle_deg, transform_from_rpy

er = pytest.importorskip('saras_drivers.endoscope_renderer')
ts = pytest.importorskip('saras_drivers.tissue_surface')

HERE = os.path.dirname(os.path.abspath(__file__))
LEFT_YAML = os.path.join(HERE, '..', '..', 'saras_drivers', 'config', 'endoscope_left.yaml')


def look_at(eye, target, up):
    """Optical frame at ``eye`` with z towards ``target`` and -y roughly along ``up``."""
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(-up, z)
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = eye
    return T


@pytest.mark.skipif(not os.path.exists(LEFT_YAML), reason='saras_drivers camera YAML not present')
def test_detect_pattern_rendered_by_endoscope_simulator():
    cam = er.CameraModel.from_yaml_file(LEFT_YAML).scaled(640, 360)
    board = er.PlanarTarget.circles()
    T_world_board = transform_from_rpy([-0.02, 0.0, 0.09], [np.pi, 0.0, 0.25])   # above the tissue
    renderer = er.SceneRenderer(cam, ts.TissueSurface.from_config(None), target=(board, T_world_board))
    pattern = CircularPattern()
    for k, (eye, up) in enumerate([([-0.02, 0.0, 0.30], [1.0, 0.0, 0.0]),
                                   ([0.03, 0.05, 0.28], [0.6, -0.8, 0.0]),
                                   ([-0.07, -0.03, 0.27], [0.0, 1.0, 0.3])]):
        T_world_cam = look_at(np.array(eye), T_world_board[:3, 3], np.array(up))
        img = renderer.render(T_world_cam)
        T_cam_pattern, rms, ids = pattern.detect(img, cam.K, cam.D)
        truth = inverse(T_world_cam) @ T_world_board
        E = inverse(truth) @ T_cam_pattern
        assert len(ids) >= 3 and rms < 1.0, (k, ids, rms)
        assert rotation_angle_deg(E[:3, :3]) < 0.5, k
        # The simulator snaps marker corners to its 0.2 mm texels: allow 1 mm.
        assert np.linalg.norm(E[:3, 3]) < 0.001, (k, E[:3, 3])
