"""Stereo calibration on real images: OpenCV's stereo checkerboard set (Debian ``opencv-doc``:
13 pairs, 640x480, 9x6 inner corners), against OpenCV's own pipeline on the same images
(``findChessboardCorners`` + ``cornerSubPix`` 11x11, ``calibrateCamera``, ``stereoCalibrate``)."""
import glob
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
import yaml

from saras_calibration import accuracy, views
from saras_calibration.corners import detect_corners
from saras_calibration.stereo import StereoCalibrationError, StereoSampleCollector, calibrate_stereo
from saras_calibration.stereo_output import report, summary, write_outputs

DATA = '/usr/share/doc/opencv-doc/examples/data'
BOARD = (9, 6)
SQUARE = 0.025   # [m]; the set's real square size is not documented, the checks are relative
SIZE = (640, 480)
HERE = os.path.dirname(os.path.abspath(__file__))

pytestmark = pytest.mark.skipif(not os.path.exists(os.path.join(DATA, 'left01.jpg')),
                                reason='OpenCV sample images absent: apt-get install opencv-doc '
                                       '(listed in scripts/apt-packages.txt)')


def _images(side):
    return [cv2.imread(f, cv2.IMREAD_GRAYSCALE) for f in sorted(glob.glob(os.path.join(DATA, side + '[0-9]*.jpg')))]


@pytest.fixture(scope='module')
def images():
    return _images('left'), _images('right')


@pytest.fixture(scope='module')
def opencv(images):
    """OpenCV's pipeline: corners, calibrateCamera per camera, stereoCalibrate, leave-one-out."""
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    corners = []
    for imgs in images:
        cs = []
        for g in imgs:
            ok, c = cv2.findChessboardCorners(g, BOARD, None)
            assert ok
            cs.append(cv2.cornerSubPix(g, c, (11, 11), (-1, -1), crit))
        corners.append(cs)
    obj = accuracy.object_points(BOARD, SQUARE)
    sol = accuracy.solve_stereo(obj, corners[0], corners[1], SIZE, extended=False)
    return sol, accuracy.cross_validate(obj, corners[0], corners[1], SIZE, folds=13)


@pytest.fixture(scope='module')
def result(images):
    return calibrate_stereo(images[0], images[1], BOARD, SQUARE)


def test_every_pair_accepted(images, result):
    assert len(images[0]) == 13
    assert result.n_views == 13


def test_rms_and_baseline_at_least_as_good_as_opencv(result, opencv):
    sol, ho = opencv
    # OpenCV's RMS on this set: 0.41 / 0.46 px; this package's: 0.18 / 0.19 px.
    assert result.reprojection_rms_px[0] <= sol.rms[0]
    assert result.reprojection_rms_px[1] <= sol.rms[1]
    assert result.holdout['left_rms_px'] <= ho['left_rms_px']
    assert result.holdout['right_rms_px'] <= ho['right_rms_px']
    assert result.holdout['transfer_rms_px'] <= ho['transfer_rms_px']
    assert abs(result.baseline_m - sol.baseline) <= 0.01 * sol.baseline
    assert result.epipolar_rms_px < 0.5


def test_uncertainties_reported(result, tmp_path):
    for cam in (result.left, result.right):
        s = cam['std']
        assert set(s) == {'fx', 'fy', 'cx', 'cy', 'k1', 'k2', 'p1', 'p2', 'k3'}
        assert all(np.isfinite(v) and v > 0 for v in s.values())
        assert s['fx'] < 0.005 * cam['K'][0, 0] and s['cx'] < 3.0
    assert 0 < result.holdout['baseline_std'] < 0.01 * result.baseline_m
    write_outputs(result, str(tmp_path))
    rep = yaml.safe_load(open(str(tmp_path / 'stereo_report.yaml')))
    assert rep == yaml.safe_load(yaml.safe_dump(report(result)))
    assert rep['std']['baseline_m'] > 0 and rep['holdout']['folds'] == 13
    assert rep['std']['left']['fx'] == pytest.approx(result.left['std']['fx'], rel=1e-4)
    assert 'hold-out' in summary(result) and '+-' in summary(result)
    left = yaml.safe_load(open(str(tmp_path / 'endoscope_left.yaml')))
    np.testing.assert_allclose(np.reshape(left['camera_matrix']['data'], (3, 3)), result.left['K'], atol=1e-3)


def test_scaled_window_beats_fixed_and_camera_calibration_refinement(images):
    obj = accuracy.object_points(BOARD, SQUARE)
    rms = {}
    for method in ('scaled_subpix', 'subpix11', 'camera_calibration'):
        cs = [detect_corners(g, BOARD, method) for g in images[0]]
        assert all(c is not None for c in cs)
        rms[method] = cv2.calibrateCamera([obj] * len(cs), cs, SIZE, None, None)[0]
    assert rms['scaled_subpix'] < 0.7 * rms['subpix11'] < rms['camera_calibration']


def test_duplicates_dropped_and_poor_coverage_explained(images):
    left, right = images
    col = StereoSampleCollector(BOARD, SQUARE)
    assert col.add(left[0], right[0])
    assert not col.add(left[0], right[0])          # the same view again
    with pytest.raises(StereoCalibrationError, match='only 1 stereo views'):
        col.calibrate()
    # Five nearly fronto-parallel views (skew < 0.1): the message asks for tilt.
    col = StereoSampleCollector(BOARD, SQUARE)
    for i in (0, 2, 3, 8, 11):                      # left01, 03, 04, 09, 13
        assert col.add(left[i], right[i])
    with pytest.raises(StereoCalibrationError, match='tilt') as err:
        col.calibrate(min_views=5)
    assert 'scale' not in str(err.value)


def test_full_collector_keeps_views_that_widen_coverage(images):
    left, right = images
    col = StereoSampleCollector(BOARD, SQUARE, max_views=3)
    for i in (0, 2, 3):                             # three views near the centre
        assert col.add(left[i], right[i])
    before = sum(p[3] for p in col.progress())
    assert col.add(left[5], right[5])               # left06: right edge, widens X
    assert col.n_views == 3 and sum(p[3] for p in col.progress()) > before
    assert not col.add(left[3], right[3])           # already kept


def test_coverage_problems_name_what_is_missing():
    # Small boards, all in the image centre, fronto-parallel.
    params = [[0.5, 0.5, 0.1, 0.02], [0.52, 0.49, 0.12, 0.03], [0.48, 0.51, 0.11, 0.01]]
    text = ' '.join(views.coverage_problems(params))
    for word in ('horizontal', 'vertical', 'scale', 'tilt'):
        assert word in text
    good = [[0.1, 0.1, 0.3, 0.3], [0.9, 0.9, 0.45, 0.05]]
    assert views.coverage_problems(good) == []


def test_cli_refuses_a_poor_set_with_the_reason(tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    cmd = [sys.executable, os.path.join(HERE, '..', 'scripts', 'stereo_calibrate_images'), '--size', '9x6',
           '--square', '0.025', '--left', os.path.join(DATA, 'left01.jpg'),
           '--right', os.path.join(DATA, 'right01.jpg'), '--output-dir', str(tmp_path)]
    out = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                         timeout=120)
    assert out.returncode == 1
    assert 'only 1 stereo views' in out.stderr and 'need 10' in out.stderr
    assert not os.path.exists(str(tmp_path / 'endoscope_left.yaml'))
