"""Hand-eye core against synthetic ground truth (independent reference: the generating X)."""
import numpy as np
import pytest

from saras_calibration.hand_eye import HandEyeError, OPENCV_METHODS, solve_hand_eye
from saras_calibration.synthetic import ecm_hand_eye_dataset, opencv_hand_eye_dataset
from saras_common.transforms import inverse, make_transform, rotation_angle_deg


def errors(X, X_true):
    E = inverse(X_true) @ X
    return rotation_angle_deg(E[:3, :3]), float(np.linalg.norm(X[:3, 3] - X_true[:3, 3]))


def test_exact_data_recovers_transform_for_every_method():
    ee, cm, X, _ = ecm_hand_eye_dataset(np.random.default_rng(3), 8, rot_noise_deg=0.0, trans_noise_m=0.0)
    for method in ['robust'] + list(OPENCV_METHODS):
        r = solve_hand_eye(ee, cm, method=method)
        rot, trans = errors(r.transform, X)
        assert rot < 1e-5 and trans < 1e-6, method
    assert r.rotation_rms_deg < 1e-5 and r.translation_rms_m < 1e-6


@pytest.mark.parametrize('seed', range(6))
def test_issue_target_20_samples_noise_and_15_percent_outliers(seed):
    """Issue 8: 20 samples, 0.5 mm / 0.1 deg noise, 15 % outliers -> < 0.2 deg and < 1 mm."""
    ee, cm, X, out = ecm_hand_eye_dataset(np.random.default_rng(seed), 20, rot_noise_deg=0.1,
                                          trans_noise_m=0.0005, outlier_fraction=0.15)
    assert len(out) == 3
    r = solve_hand_eye(ee, cm)
    rot, trans = errors(r.transform, X)
    assert rot < 0.2 and trans < 1e-3, (rot, trans)
    assert not any(r.inliers[i] for i in out), 'an outlier was kept'
    assert r.n_inliers >= 15
    # The reported residuals are those of the inliers: noise-sized, not outlier-sized.
    assert r.rotation_rms_deg < 0.5 and r.translation_rms_m < 3e-3
    # The plain OpenCV solvers are ruined by the same outliers (the test data really is bad).
    rot_cv, trans_cv = errors(solve_hand_eye(ee, cm, method='park').transform, X)
    assert rot_cv > 3 * rot or trans_cv > 3 * trans


def test_robust_beats_opencv_on_opencv_noise_model():
    """Averaged over trials of OpenCV's own scenario, clean data: at least as good as the best."""
    acc = {m: [] for m in ['robust'] + list(OPENCV_METHODS)}
    for seed in range(8):
        ee, cm, X, _ = opencv_hand_eye_dataset(np.random.default_rng(100 + seed), 10)
        for m in acc:
            acc[m].append(errors(solve_hand_eye(ee, cm, method=m).transform, X))
    mean = {m: np.mean(v, axis=0) for m, v in acc.items()}
    best_rot = min(mean[m][0] for m in OPENCV_METHODS)
    assert mean['robust'][0] <= best_rot


def test_input_errors():
    ee, cm, _, _ = ecm_hand_eye_dataset(np.random.default_rng(0), 6)
    with pytest.raises(HandEyeError, match='mismatched'):
        solve_hand_eye(ee, cm[:-1])
    with pytest.raises(HandEyeError, match='at least 3'):
        solve_hand_eye(ee[:2], cm[:2])
    bad = [T.copy() for T in ee]
    bad[2][:3, :3] *= 1.1
    with pytest.raises(HandEyeError, match=r'ee_poses\[2\].*not rigid'):
        solve_hand_eye(bad, cm)
    bad = [T.copy() for T in cm]
    bad[1][0, 3] = np.nan
    with pytest.raises(HandEyeError, match='NaN'):
        solve_hand_eye(ee, bad)
    with pytest.raises(HandEyeError, match='unknown'):
        solve_hand_eye(ee, cm, method='magic')
    with pytest.raises(HandEyeError):
        solve_hand_eye(None, cm)


def test_motions_without_enough_rotation():
    rng = np.random.default_rng(1)
    X = make_transform(None, [0.0, 0.0, 0.01])
    M = make_transform(None, [0.0, 0.0, -0.2])
    # Pure translations: rotation of A X = X B undetermined.
    ee = [make_transform(None, rng.normal(0, 0.02, 3)) for _ in range(6)]
    cm = [inverse(X) @ inverse(T) @ M for T in ee]
    with pytest.raises(HandEyeError, match='enough rotation'):
        solve_hand_eye(ee, cm)
    # Rotations about a single axis only.
    from scipy.spatial.transform import Rotation
    ee = [make_transform(Rotation.from_rotvec([0, 0, a]).as_matrix(), rng.normal(0, 0.02, 3))
          for a in np.linspace(0, 1.0, 6)]
    cm = [inverse(X) @ inverse(T) @ M for T in ee]
    with pytest.raises(HandEyeError, match='same axis'):
        solve_hand_eye(ee, cm)
