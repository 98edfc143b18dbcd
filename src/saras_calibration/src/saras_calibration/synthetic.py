"""Synthetic ground truth for tests, benchmarks and simulators (deterministic given a seed).

* :func:`opencv_hand_eye_dataset`: OpenCV's own hand-eye test scenario
  (modules/calib3d/test/test_calibration_hand_eye.cpp, eye-in-hand): random poses in the same
  ranges, noise added to the rotation vectors and translations (camera 0.002 rad / 5 mm,
  robot 0.001 rad / 1 mm by default).
* :func:`ecm_hand_eye_dataset`: endoscope-scale scenario (marker 8-15 cm in front of the
  camera, ECM rotating about its remote centre of motion).
* :func:`corrupt_pose`: a gross marker-detection error (outlier).
* :func:`render_checkerboard`: ray-cast image of a checkerboard seen by a pinhole camera with
  plumb-bob distortion (used to test the stereo intrinsics calibration).
"""
import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from saras_common.transforms import inverse, make_transform

__all__ = ['random_pose', 'perturb_pose', 'corrupt_pose', 'opencv_hand_eye_dataset',
           'ecm_hand_eye_dataset', 'render_checkerboard', 'checkerboard_views']


def random_pose(rng, min_angle, max_angle, min_t, max_t, random_sign=True):
    """Random pose as in OpenCV's test: angle in [min, max] rad about a random axis, each
    translation component in [min_t, max_t] m with a random sign."""
    axis = rng.uniform(-1.0, 1.0, 3)
    axis /= np.linalg.norm(axis)
    theta = rng.uniform(min_angle, max_angle)
    t = rng.uniform(min_t, max_t, 3)
    if random_sign:
        t *= np.sign(rng.uniform(-1.0, 1.0, 3))
    return make_transform(Rotation.from_rotvec(theta * axis).as_matrix(), t)


def perturb_pose(T, rng, rot_sigma, trans_sigma):
    """OpenCV's noise model: Gaussian noise added to the rotation vector [rad] and the
    translation [m] of ``T``."""
    rv = Rotation.from_matrix(T[:3, :3]).as_rotvec() + rng.normal(0.0, rot_sigma, 3)
    return make_transform(Rotation.from_rotvec(rv).as_matrix(), T[:3, 3] + rng.normal(0.0, trans_sigma, 3))


def corrupt_pose(T, rng, min_angle_deg=10.0, max_angle_deg=40.0, min_t=0.02, max_t=0.10):
    """A gross detection error: ``T`` rotated by 10-40 deg about a random axis and shifted by
    2-10 cm in a random direction (e.g. an ArUco pose flip or a wrong marker)."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    E = make_transform(Rotation.from_rotvec(np.radians(rng.uniform(min_angle_deg, max_angle_deg)) * axis).as_matrix(),
                       d * rng.uniform(min_t, max_t))
    return T @ E


def opencv_hand_eye_dataset(rng, n_poses=10, cam_noise=(0.002, 0.005), robot_noise=(0.001, 0.001),
                            n_outliers=0):
    """OpenCV test scenario. Returns (ee_poses, marker_poses, X_true, outlier_indices)."""
    X = random_pose(rng, np.radians(10), np.radians(50), 0.05, 0.5)
    T_base_target = random_pose(rng, np.radians(5), np.radians(85), 0.5, 3.5)
    ee, cm = [], []
    for _ in range(n_poses):
        T_be = random_pose(rng, np.radians(5), np.radians(45), 0.5, 1.5)
        T_cm = inverse(X) @ inverse(T_be) @ T_base_target
        if cam_noise is not None:
            T_cm = perturb_pose(T_cm, rng, *cam_noise)
        if robot_noise is not None:
            T_be = perturb_pose(T_be, rng, *robot_noise)
        ee.append(T_be)
        cm.append(T_cm)
    out = sorted(rng.choice(n_poses, n_outliers, replace=False).tolist()) if n_outliers else []
    for i in out:
        cm[i] = corrupt_pose(cm[i], rng)
    return ee, cm, X, out


def ecm_hand_eye_dataset(rng, n_poses=20, rot_noise_deg=0.1, trans_noise_m=0.0005,
                         outlier_fraction=0.0, X=None):
    """Endoscope-scale scenario: the ECM pivots about its RCM (base origin), the camera looks
    at a marker on the table 3-25 cm ahead. Isotropic Gaussian noise on both the marker and the
    end-effector poses whose RMS magnitude is ``rot_noise_deg`` (rotation) and
    ``trans_noise_m`` (translation), i.e. ``rot_noise_deg / sqrt(3)`` per axis.

    Returns (ee_poses, marker_poses, X_true, outlier_indices).
    """
    if X is None:
        # Camera 5 mm beyond the tip, tilted 30 deg (angled endoscope) - typical da Vinci.
        X = make_transform(Rotation.from_euler('xyz', [np.radians(30), 0.0, np.radians(5)]).as_matrix(),
                           [0.002, -0.003, 0.005])
    T_base_marker = make_transform(Rotation.from_euler('xyz', [np.pi, 0.0, 0.3]).as_matrix(), [0.0, 0.02, -0.20])
    ee, cm = [], []
    rn = np.radians(rot_noise_deg) / np.sqrt(3.0)
    tn = trans_noise_m / np.sqrt(3.0)
    while len(ee) < n_poses:
        # Tool pointing down (-z of base) with +-25 deg pitch/yaw, +-60 deg roll, 6-12 cm insertion.
        yaw, pitch, roll = rng.uniform(-0.45, 0.45), rng.uniform(-0.45, 0.45), rng.uniform(-1.0, 1.0)
        R = Rotation.from_euler('xyz', [np.pi + pitch, yaw, roll]).as_matrix()
        T_be = make_transform(R, R @ np.array([0.0, 0.0, rng.uniform(0.06, 0.12)]))
        T_cm = inverse(X) @ inverse(T_be) @ T_base_marker
        if not 0.03 < T_cm[2, 3] < 0.25:   # marker must be in front of the camera
            continue
        ee.append(perturb_pose(T_be, rng, rn, tn))
        cm.append(perturb_pose(T_cm, rng, rn, tn))
    n_out = int(round(outlier_fraction * n_poses))
    out = sorted(rng.choice(n_poses, n_out, replace=False).tolist()) if n_out else []
    for i in out:
        cm[i] = corrupt_pose(cm[i], rng)
    return ee, cm, X, out


def render_checkerboard(K, D, size, T_cam_board, cols, rows, square, margin=1, blur_sigma=0.6):
    """Ray-cast a checkerboard into a grey image.

    :param K: 3x3 camera matrix [px]; ``D``: plumb-bob distortion (k1, k2, p1, p2, k3).
    :param size: (width, height) [px].
    :param T_cam_board: pose of the board in the camera optical frame [m]. Board frame: origin
        at the first inner corner, x along ``cols``, y along ``rows``, z into the board.
    :param cols, rows: inner corners per row / column; ``square``: square side [m].
    :param margin: white border width in squares around the pattern.
    :returns: uint8 image (white background, black squares).
    """
    w, h = size
    uv = np.stack(np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64)), -1).reshape(-1, 1, 2)
    xy = cv2.undistortPoints(uv, K, D).reshape(-1, 2)
    rays = np.hstack([xy, np.ones((len(xy), 1))])
    Rb, tb = T_cam_board[:3, :3], T_cam_board[:3, 3]
    n = Rb[:, 2]
    denom = rays @ n
    s = (n @ tb) / np.where(np.abs(denom) < 1e-12, 1e-12, denom)
    P = rays * s[:, None] - tb
    bc = P @ Rb            # board coordinates (x, y, ~0)
    i = np.floor(bc[:, 0] / square) + 1
    j = np.floor(bc[:, 1] / square) + 1
    inside = (i >= 0) & (i <= cols) & (j >= 0) & (j <= rows) & (s > 0)
    black = inside & (((i + j) % 2) == 0)
    paper = (i >= -margin) & (i <= cols + margin) & (j >= -margin) & (j <= rows + margin) & (s > 0)
    img = np.full(len(xy), 90.0)
    img[paper] = 235.0
    img[black] = 20.0
    img = img.reshape(h, w)
    if blur_sigma > 0:
        img = cv2.GaussianBlur(img, (0, 0), blur_sigma)
    return np.clip(img, 0, 255).astype(np.uint8)


def checkerboard_views(rng, n_views, cols, rows, square, distance=(0.25, 0.45), tilt_deg=35.0,
                       spread=0.06):
    """Random board poses in front of a camera (board centred near the optical axis, tilted).

    :returns: list of 4x4 ``T_cam_board`` [m].
    """
    views = []
    centre = np.array([(cols - 1) * square / 2.0, (rows - 1) * square / 2.0, 0.0])
    for _ in range(n_views):
        ang = np.radians(rng.uniform(-tilt_deg, tilt_deg, 2))
        R = Rotation.from_euler('xyz', [ang[0], ang[1], rng.uniform(-0.3, 0.3)]).as_matrix()
        c = np.array([rng.uniform(-spread, spread), rng.uniform(-spread * 0.75, spread * 0.75),
                      rng.uniform(*distance)])
        views.append(make_transform(R, c - R @ centre))
    return views
