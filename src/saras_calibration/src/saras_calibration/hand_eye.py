"""Eye-on-hand calibration: pose of the endoscope camera in the ECM end-effector frame.

Problem: the ECM reports ``T_base_ee[i]`` (end effector in the arm base) and a marker detector
reports ``T_cam_marker[i]`` (marker in the camera); the marker is fixed in the base, so
``T_base_marker = T_base_ee[i] @ X @ T_cam_marker[i]`` for every sample, with the unknown
``X = T_ee_cam``. Equivalently ``A X = X B`` on relative motions (the OpenCV solvers).

:func:`solve_hand_eye` (``method='robust'``, default):

1. validates the input (rigid 4x4, equal lengths, N >= 3, enough rotation about two axes);
2. least-median-of-squares search over minimal 3-sample subsets solved with OpenCV's Park
   method; every candidate is scored on *per-sample* residuals (each sample predicts the
   marker pose in the camera; a bad marker detection only spoils its own residual);
3. initial inliers = samples whose rotation and translation residuals are below
   ``3 x median`` of the best candidate (or the absolute thresholds given by the caller);
4. nonlinear refinement (``scipy.optimize.least_squares``) of ``X`` and ``T_base_marker`` on
   the inliers; each sample's 6-D residual is whitened by its own covariance, propagated from
   camera noise and robot noise (including the lever arm of the robot's rotation noise); the
   four noise levels are maximum-likelihood estimates from the residuals. Inliers are then
   re-classified with a chi-square (6 dof, 99.9 %) gate on the Mahalanobis distance and the
   refinement repeated (3 rounds).

Units: metres and radians in arrays, degrees only in names ending in ``_deg``.
"""
import itertools
from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.optimize import least_squares, minimize
from scipy.spatial.transform import Rotation

from saras_common.transforms import (average_rotation, inverse, make_transform, validate_transforms)

__all__ = ['HandEyeError', 'HandEyeResult', 'solve_hand_eye', 'opencv_hand_eye', 'OPENCV_METHODS',
           'hand_eye_residuals', 'check_rotation_excitation']

#: OpenCV ``calibrateHandEye`` methods by lower-case name.
OPENCV_METHODS = {
    'tsai': cv2.CALIB_HAND_EYE_TSAI,
    'park': cv2.CALIB_HAND_EYE_PARK,
    'horaud': cv2.CALIB_HAND_EYE_HORAUD,
    'andreff': cv2.CALIB_HAND_EYE_ANDREFF,
    'daniilidis': cv2.CALIB_HAND_EYE_DANIILIDIS,
}

# Lower bounds of the automatic inlier thresholds, so that noise-free data does not produce
# a zero threshold: 0.005 deg and 10 um.
_MIN_ROT_THRESHOLD = np.radians(0.005)
_MIN_TRANS_THRESHOLD = 1e-5
#: 99.9 % quantile of the chi-square distribution with 6 degrees of freedom.
_CHI2_6DOF_999 = 22.458


class HandEyeError(ValueError):
    """Bad input to, or failure of, the hand-eye calibration (message says which)."""


@dataclass
class HandEyeResult:
    """Result of :func:`solve_hand_eye`.

    :ivar transform: 4x4 ``T_ee_cam`` (camera optical frame in the end-effector frame) [m].
    :ivar inliers: one bool per input sample, False for samples rejected as outliers.
    :ivar rotation_rms_deg: RMS over inliers of the rotation residual [deg].
    :ivar translation_rms_m: RMS over inliers of the translation residual [m].
    :ivar marker_in_base: 4x4 ``T_base_marker`` estimated jointly [m].
    :ivar rotation_residuals_deg: per-sample rotation residual [deg] (all samples).
    :ivar translation_residuals_m: per-sample translation residual [m] (all samples).
    :ivar method: solver used.
    """
    transform: np.ndarray
    inliers: list
    rotation_rms_deg: float
    translation_rms_m: float
    marker_in_base: np.ndarray
    rotation_residuals_deg: np.ndarray = field(repr=False)
    translation_residuals_m: np.ndarray = field(repr=False)
    method: str = 'robust'

    @property
    def n_inliers(self):
        return int(np.count_nonzero(self.inliers))


def _validate(ee_poses, marker_poses):
    if ee_poses is None or marker_poses is None:
        raise HandEyeError('ee_poses and marker_poses must be lists of 4x4 transforms, got None')
    ee_list, cm_list = list(ee_poses), list(marker_poses)
    if len(ee_list) != len(cm_list):
        raise HandEyeError('mismatched list lengths: %d ee_poses but %d marker_poses'
                           % (len(ee_list), len(cm_list)))
    if len(ee_list) < 3:
        raise HandEyeError('hand-eye calibration needs at least 3 samples, got %d' % len(ee_list))
    try:
        ee = validate_transforms(ee_list, 'ee_poses')
        cm = validate_transforms(cm_list, 'marker_poses')
    except ValueError as exc:
        raise HandEyeError(str(exc))
    return ee, cm


def check_rotation_excitation(ee_poses, min_rotation_deg=2.0, min_axis_angle_deg=10.0):
    """Raise :class:`HandEyeError` unless the end effector rotated enough about two axes.

    The rotation part of ``A X = X B`` is only determined if at least two relative motions
    rotate by ``min_rotation_deg`` or more about axes at least ``min_axis_angle_deg`` apart.

    :returns: (largest relative rotation [deg], largest angle between motion axes [deg]).
    """
    R = np.asarray(ee_poses)[:, :3, :3]
    n = len(R)
    i, j = np.triu_indices(n, 1)
    rel = np.einsum('nji,njk->nik', R[i], R[j])  # R_i^T R_j
    rv = Rotation.from_matrix(rel).as_rotvec()
    ang = np.linalg.norm(rv, axis=1)
    max_rot = np.degrees(ang.max()) if len(ang) else 0.0
    big = ang >= np.radians(min_rotation_deg)
    if np.count_nonzero(big) < 2:
        raise HandEyeError(
            'hand-eye motions without enough rotation: need two relative motions of at least '
            '%.1f deg, largest is %.2f deg; rotate the endoscope more between samples'
            % (min_rotation_deg, max_rot))
    axes = rv[big] / ang[big, None]
    if len(axes) > 400:
        axes = axes[np.linspace(0, len(axes) - 1, 400).astype(int)]
    cosang = np.clip(np.abs(axes @ axes.T), 0.0, 1.0)
    max_axis = np.degrees(np.arccos(cosang.min()))
    if max_axis < min_axis_angle_deg:
        raise HandEyeError(
            'hand-eye motions without enough rotation: all rotations are about nearly the same axis '
            '(largest angle between rotation axes %.2f deg < %.1f deg); rotate about a second axis'
            % (max_axis, min_axis_angle_deg))
    return max_rot, max_axis


def opencv_hand_eye(ee_poses, marker_poses, method='park'):
    """``T_ee_cam`` from OpenCV ``calibrateHandEye`` (no validation, no outlier rejection)."""
    ee = np.asarray(ee_poses, dtype=float)
    cm = np.asarray(marker_poses, dtype=float)
    try:
        R, t = cv2.calibrateHandEye(list(ee[:, :3, :3]), list(ee[:, :3, 3:4]),
                                    list(cm[:, :3, :3]), list(cm[:, :3, 3:4]),
                                    method=OPENCV_METHODS[method])
    except cv2.error as exc:
        raise HandEyeError('OpenCV %s hand-eye solver failed: %s' % (method, str(exc).strip().splitlines()[-1]))
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
        raise HandEyeError('OpenCV %s hand-eye solver returned NaN (degenerate motions)' % method)
    # Re-orthonormalise (some methods return a slightly non-orthogonal matrix).
    return make_transform(average_rotation([R]), t)


def _marker_in_base(X, ee, cm):
    """Consensus ``T_base_marker`` of the samples given ``X`` (chordal mean, mean translation)."""
    T = ee @ X @ cm
    return make_transform(average_rotation(T[:, :3, :3]), T[:, :3, 3].mean(axis=0))


def hand_eye_residuals(X, T_base_marker, ee_poses, marker_poses):
    """Per-sample residuals of a hand-eye solution.

    Each sample predicts the marker pose in the camera, ``inv(X) inv(T_base_ee) T_base_marker``,
    compared with the measured ``T_cam_marker``.

    :returns: (rotation residual [rad], translation residual [m], rotation vectors (N, 3) [rad],
        translation errors (N, 3) [m], in the camera frame).
    """
    ee = np.asarray(ee_poses)
    cm = np.asarray(marker_poses)
    Xi = inverse(X)
    ee_inv = np.zeros_like(ee)
    ee_inv[:, :3, :3] = np.transpose(ee[:, :3, :3], (0, 2, 1))
    ee_inv[:, :3, 3] = -np.einsum('nji,nj->ni', ee[:, :3, :3], ee[:, :3, 3])
    ee_inv[:, 3, 3] = 1.0
    pred = Xi @ ee_inv @ T_base_marker
    dR = np.einsum('nji,njk->nik', cm[:, :3, :3], pred[:, :3, :3])
    rv = Rotation.from_matrix(dR).as_rotvec()
    dt = pred[:, :3, 3] - cm[:, :3, 3]
    return np.linalg.norm(rv, axis=1), np.linalg.norm(dt, axis=1), rv, dt


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _residual_jacobians(X, M, ee):
    """Jacobians of the residual of :func:`hand_eye_residuals` (rotation in the marker frame,
    translation in the camera frame) w.r.t. a right perturbation (rotation, translation) of
    ``T_base_ee`` (in the end-effector frame). Returns (N, 6, 6)."""
    Xi = inverse(X)
    Ri, pi = Xi[:3, :3], Xi[:3, 3]
    Ad = np.zeros((6, 6))
    Ad[:3, :3] = Ri
    Ad[3:, :3] = _skew(pi) @ Ri
    Ad[3:, 3:] = Ri
    J = np.zeros((len(ee), 6, 6))
    for k, T in enumerate(ee):
        pred = Xi @ inverse(T) @ M
        G = np.zeros((6, 6))
        G[:3, :3] = pred[:3, :3].T
        G[3:, :3] = -_skew(pred[:3, 3])
        G[3:, 3:] = np.eye(3)
        J[k] = -G @ Ad
    return J


def _covariances(J, s):
    """Per-sample 6x6 residual covariance for noise standard deviations
    ``s = (camera rot [rad], camera trans [m], robot rot [rad], robot trans [m])``."""
    Sc = np.diag([s[0] ** 2] * 3 + [s[1] ** 2] * 3)
    Sr = np.diag([s[2] ** 2] * 3 + [s[3] ** 2] * 3)
    return Sc[None] + J @ Sr @ np.transpose(J, (0, 2, 1))


def _fit_noise(e, J, s0):
    """Maximum-likelihood noise standard deviations given residuals ``e`` (N, 6)."""
    def nll(logs):
        C = _covariances(J, np.exp(logs))
        sign, logdet = np.linalg.slogdet(C)
        return float(np.sum(logdet) + np.einsum('ni,ni->', e, np.linalg.solve(C, e[..., None])[..., 0]))
    sol = minimize(nll, np.log(s0), method='Nelder-Mead', options={'xatol': 0.02, 'fatol': 1e-3, 'maxiter': 400})
    return np.exp(sol.x)


def _refine(X0, M0, ee, cm, s):
    """Joint least-squares refinement of ``X`` and ``T_base_marker`` on the given samples,
    residuals whitened with the per-sample covariance implied by the noise model ``s``."""
    W = np.linalg.cholesky(np.linalg.inv(_covariances(_residual_jacobians(X0, M0, ee), s)))

    def unpack(p):
        X = X0 @ make_transform(Rotation.from_rotvec(p[0:3]).as_matrix(), p[3:6])
        M = M0 @ make_transform(Rotation.from_rotvec(p[6:9]).as_matrix(), p[9:12])
        return X, M

    def fun(p):
        X, M = unpack(p)
        _, _, rv, dt = hand_eye_residuals(X, M, ee, cm)
        e = np.hstack([rv, dt])
        return np.einsum('nji,nj->ni', W, e).ravel()

    sol = least_squares(fun, np.zeros(12), method='lm', x_scale='jac')
    return unpack(sol.x)


def _thresholds(r, t, rot_thr, trans_thr):
    thr_r = rot_thr if rot_thr is not None else max(3.0 * np.median(r), _MIN_ROT_THRESHOLD)
    thr_t = trans_thr if trans_thr is not None else max(3.0 * np.median(t), _MIN_TRANS_THRESHOLD)
    return thr_r, thr_t


def _candidate_subsets(n, trials, rng):
    total = n * (n - 1) * (n - 2) // 6
    if total <= trials:
        return list(itertools.combinations(range(n), 3))
    return [tuple(rng.choice(n, 3, replace=False)) for _ in range(trials)]


def _subset_ok(ee_sub, min_rotation_rad, min_axis_cos):
    R = ee_sub[:, :3, :3]
    rv1 = Rotation.from_matrix(R[0].T @ R[1]).as_rotvec()
    rv2 = Rotation.from_matrix(R[0].T @ R[2]).as_rotvec()
    a1, a2 = np.linalg.norm(rv1), np.linalg.norm(rv2)
    if a1 < min_rotation_rad or a2 < min_rotation_rad:
        return False
    return abs(rv1 @ rv2) / (a1 * a2) < min_axis_cos


def _consensus(ee, cm, trials, rng, min_rotation_deg, min_axis_angle_deg, rot_thr, trans_thr):
    """Robust initial estimate: the 3-sample solution (Park) whose residual medians over all samples
    are smallest, and its inliers. Returns (X or None, inlier mask)."""
    n = len(ee)
    min_cos = np.cos(np.radians(min_axis_angle_deg))
    cands = []
    for sub in _candidate_subsets(n, trials, rng):
        sub = list(sub)
        if not _subset_ok(ee[sub], np.radians(min_rotation_deg), min_cos):
            continue
        try:
            Xc = opencv_hand_eye(ee[sub], cm[sub], 'park')
        except HandEyeError:
            continue
        if not np.all(np.isfinite(Xc)):
            continue
        Mc = _marker_in_base(Xc, ee[sub], cm[sub])
        r, t, _, _ = hand_eye_residuals(Xc, Mc, ee, cm)
        cands.append((np.median(r), np.median(t), Xc, r, t))
    if not cands:
        return None, np.ones(n, dtype=bool)
    mr = max(min(c[0] for c in cands), 1e-12)
    mt = max(min(c[1] for c in cands), 1e-15)
    _, _, X, r, t = min(cands, key=lambda c: c[0] / mr + c[1] / mt)
    thr_r, thr_t = _thresholds(r, t, rot_thr, trans_thr)
    inl = (r <= thr_r) & (t <= thr_t)
    if np.count_nonzero(inl) < 3:
        inl = np.ones(n, dtype=bool)
    return X, inl


def _robust_refine(X, M, ee, cm, inl, rot_thr, trans_thr):
    """Alternates the weighted refinement, the noise-model fit and the inlier gate (3 rounds, then
    a final refinement). Returns (X, M, inlier mask)."""
    # Initial noise model: rotation/translation spread shared equally by camera and robot.
    r, t, _, _ = hand_eye_residuals(X, M, ee[inl], cm[inl])
    sr = max(np.median(r) / 1.54, 1e-7) / np.sqrt(2.0)
    st = max(np.median(t) / 1.54, 1e-9) / np.sqrt(2.0)
    s = np.array([sr, st, sr, st])
    for _ in range(3):
        X, M = _refine(X, M, ee[inl], cm[inl], s)
        r_all, t_all, rv, dt = hand_eye_residuals(X, M, ee, cm)
        if np.count_nonzero(inl) >= 6:
            s = _fit_noise(np.hstack([rv, dt])[inl], _residual_jacobians(X, M, ee[inl]), s)
            s = np.maximum(s, [1e-7, 1e-9, 1e-7, 1e-9])
        if rot_thr is None and trans_thr is None and np.count_nonzero(inl) >= 6:
            # Mahalanobis distance under the fitted noise model (corrected for the 12
            # estimated parameters), chi-square 6 dof at 99.9 %.
            k = np.count_nonzero(inl)
            C = _covariances(_residual_jacobians(X, M, ee), s * np.sqrt(6.0 * k / (6.0 * k - 12.0)))
            e = np.hstack([rv, dt])
            d2 = np.einsum('ni,ni->n', e, np.linalg.solve(C, e[..., None])[..., 0])
            new_inl = d2 <= _CHI2_6DOF_999
        else:
            thr_r, thr_t = _thresholds(r_all[inl], t_all[inl], rot_thr, trans_thr)
            new_inl = (r_all <= thr_r) & (t_all <= thr_t)
        if np.count_nonzero(new_inl) >= 3:
            inl = new_inl
    X, M = _refine(X, M, ee[inl], cm[inl], s)
    return X, M, inl


def solve_hand_eye(ee_poses, marker_poses, method='robust', min_rotation_deg=2.0,
                   min_axis_angle_deg=10.0, ransac_trials=200, rotation_threshold_deg=None,
                   translation_threshold_m=None, min_inlier_fraction=0.5, seed=0):
    """Solve the eye-on-hand calibration ``T_ee_cam``.

    :param ee_poses: list of 4x4 ``T_base_ee`` (ECM end effector in its base) [m].
    :param marker_poses: list of 4x4 ``T_cam_marker`` (marker in the camera optical frame) [m].
    :param method: ``'robust'`` (outlier rejection + refinement) or one of
        :data:`OPENCV_METHODS` (plain OpenCV, every sample an inlier).
    :param min_rotation_deg: minimum relative rotation of a useful motion [deg].
    :param min_axis_angle_deg: minimum angle between two motion axes [deg].
    :param ransac_trials: maximum number of 3-sample candidates of the robust search.
    :param rotation_threshold_deg: absolute inlier threshold on the rotation residual [deg];
        default: automatic (3 x median, then the chi-square gate of the noise model).
    :param translation_threshold_m: absolute inlier threshold on the translation residual [m];
        default: automatic.
    :param min_inlier_fraction: fail if fewer samples than this fraction are inliers.
    :param seed: seed of the random subset draw (results are reproducible).
    :returns: :class:`HandEyeResult`.
    :raises HandEyeError: fewer than 3 samples, mismatched lengths, non-rigid transforms,
        not enough rotation, unknown method, or too many outliers.
    """
    ee, cm = _validate(ee_poses, marker_poses)
    n = len(ee)
    if method != 'robust' and method not in OPENCV_METHODS:
        raise HandEyeError('unknown hand-eye method %r (robust, %s)' % (method, ', '.join(OPENCV_METHODS)))
    check_rotation_excitation(ee, min_rotation_deg, min_axis_angle_deg)
    rot_thr = None if rotation_threshold_deg is None else np.radians(rotation_threshold_deg)
    trans_thr = translation_threshold_m

    if method in OPENCV_METHODS:
        X = opencv_hand_eye(ee, cm, method)
        M = _marker_in_base(X, ee, cm)
        inl = np.ones(n, dtype=bool)
    else:
        X, inl = None, np.ones(n, dtype=bool)
        if n >= 6:
            X, inl = _consensus(ee, cm, ransac_trials, np.random.default_rng(seed), min_rotation_deg,
                                min_axis_angle_deg, rot_thr, trans_thr)
        if X is None or np.count_nonzero(inl) >= 3:
            X = opencv_hand_eye(ee[inl], cm[inl], 'park')
        M = _marker_in_base(X, ee[inl], cm[inl])
        X, M, inl = _robust_refine(X, M, ee, cm, inl, rot_thr, trans_thr)

    if np.count_nonzero(inl) < max(3, int(np.ceil(min_inlier_fraction * n))):
        raise HandEyeError('too many outliers: only %d of %d samples are consistent'
                           % (np.count_nonzero(inl), n))
    if not np.all(inl):
        check_rotation_excitation(ee[inl], min_rotation_deg, min_axis_angle_deg)
    r_all, t_all, _, _ = hand_eye_residuals(X, M, ee, cm)
    return HandEyeResult(
        transform=X, inliers=[bool(b) for b in inl],
        rotation_rms_deg=float(np.degrees(np.sqrt(np.mean(r_all[inl] ** 2)))),
        translation_rms_m=float(np.sqrt(np.mean(t_all[inl] ** 2))),
        marker_in_base=M, rotation_residuals_deg=np.degrees(r_all), translation_residuals_m=t_all,
        method=method)
