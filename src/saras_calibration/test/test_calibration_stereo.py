"""Stereo intrinsics/extrinsics through camera_calibration on synthetic checkerboard images.

The images are ray-cast here with known K, D and baseline (independent of the endoscope
simulator); the calibration must recover them.
"""
import numpy as np
import pytest
import yaml

from saras_calibration.stereo import StereoCalibrationError, StereoSampleCollector, calibrate_stereo, parse_board_size
from saras_calibration.synthetic import checkerboard_views, render_checkerboard
from saras_common.transforms import make_transform

SIZE = (640, 480)
K_L = np.array([[700.0, 0, 322.0], [0, 705.0, 236.0], [0, 0, 1]])
D_L = np.array([-0.12, 0.05, 0.001, -0.0005, 0.0])
K_R = np.array([[702.0, 0, 318.0], [0, 706.0, 242.0], [0, 0, 1]])
D_R = np.array([-0.10, 0.03, 0.0, 0.0, 0.0])
BASELINE = 0.005
BOARD = (8, 6)
SQUARE = 0.005


@pytest.fixture(scope='module')
def result():
    rng = np.random.default_rng(1)
    T_right_left = make_transform(None, [-BASELINE, 0.0, 0.0])   # right eye 5 mm to the right
    views = checkerboard_views(rng, 26, BOARD[0], BOARD[1], SQUARE, distance=(0.05, 0.09), spread=0.01)
    left = [render_checkerboard(K_L, D_L, SIZE, T, BOARD[0], BOARD[1], SQUARE) for T in views]
    right = [render_checkerboard(K_R, D_R, SIZE, T_right_left @ T, BOARD[0], BOARD[1], SQUARE) for T in views]
    return calibrate_stereo(left, right, BOARD, SQUARE)


def test_intrinsics_recovered(result):
    for cam, K in ((result.left, K_L), (result.right, K_R)):
        np.testing.assert_allclose(np.diag(cam['K'])[:2], np.diag(K)[:2], rtol=0.005)
        np.testing.assert_allclose(cam['K'][:2, 2], K[:2, 2], atol=2.0)
    # Distortion: compare the effect, not the (correlated) coefficients: pixel positions over
    # the central 75 % of the image (where the board was shown) within 1 px of the truth (the
    # distortion itself moves these points by up to 8 px; the principal point is within 2 px).
    import cv2
    g = np.array([[x, y, 1.0] for x in np.linspace(-0.34, 0.34, 9) for y in np.linspace(-0.25, 0.25, 7)])
    for cam, K, D in ((result.left, K_L, D_L), (result.right, K_R, D_R)):
        truth = cv2.projectPoints(g, np.zeros(3), np.zeros(3), K, D)[0].reshape(-1, 2)
        est = cv2.projectPoints(g, np.zeros(3), np.zeros(3), cam['K'], cam['D'])[0].reshape(-1, 2)
        assert np.max(np.linalg.norm(truth - est, axis=1)) < 1.0


def test_extrinsics_and_quality(result):
    assert result.n_views >= 8
    np.testing.assert_allclose(result.T, [-BASELINE, 0, 0], atol=1e-4)
    assert abs(result.baseline_m - BASELINE) < 5e-5
    assert np.degrees(np.arccos((np.trace(result.R) - 1) / 2)) < 0.2
    assert max(result.reprojection_rms_px) < 0.5
    assert result.epipolar_rms_px < 0.5


def test_yaml_is_camera_calibration_format(result, tmp_path):
    d = yaml.safe_load(result.left_yaml)
    assert d['image_width'] == SIZE[0] and d['image_height'] == SIZE[1]
    assert d['camera_name'] == 'endoscope_left'
    assert d['distortion_model'] == 'plumb_bob'
    np.testing.assert_allclose(np.reshape(d['camera_matrix']['data'], (3, 3)), result.left['K'], atol=1e-3)
    r = yaml.safe_load(result.right_yaml)
    P = np.reshape(r['projection_matrix']['data'], (3, 4))
    assert P[0, 3] < 0 and abs(-P[0, 3] / P[0, 0] - BASELINE) < 1e-4  # Tx = -fx * baseline


def test_bad_input():
    with pytest.raises(ValueError, match='8x6'):
        parse_board_size('8-6')
    assert parse_board_size('8x6') == (8, 6)
    col = StereoSampleCollector(BOARD, SQUARE)
    blank = np.full((480, 640), 128, np.uint8)
    assert not col.add(blank, blank)
    assert not col.add(blank, np.zeros((10, 10), np.uint8))
    assert not col.add(None, blank)
    with pytest.raises(StereoCalibrationError, match='only 0'):
        col.calibrate()
    with pytest.raises(ValueError, match='square'):
        StereoSampleCollector(BOARD, -1.0)
