"""Choose the passive Positioning-Arm set-up pose that puts the RCM on a trocar (numpy only).

Used by ``scripts/solve_pa_setup`` to (re)write ``config/saras_arms.yaml`` when the arm bases
(``mesa_*/sbs_world`` in world_frames.yaml) or the trocar positions change.
"""
import numpy as np

from saras_description.kinematics import saras_arm_joint_limits, saras_arm_rcm_in_base
from saras_common.transforms import inverse

#: Comfortable posture the solver is pulled toward (elbow up, wrist bent down) [rad].
NOMINAL_PA = np.array([0.0, 0.5, 0.0, 1.3, 0.0, 1.0, 0.0])


def rcm_targets_in_base(base_in_world, rcm_in_world, site_in_world):
    """RCM position and shaft direction (RCM -> site, unit) expressed in the arm base frame."""
    inv = inverse(base_in_world)
    rcm = (inv @ np.append(rcm_in_world, 1.0))[:3]
    site = (inv @ np.append(site_in_world, 1.0))[:3]
    d = site - rcm
    return rcm, d / np.linalg.norm(d)


def _residual(q, rcm, direction, weight):
    t = saras_arm_rcm_in_base(q)
    # The rcm frame's z axis points out of the patient: it must equal -direction.
    return np.concatenate([t[:3, 3] - rcm, 0.2 * (t[:3, 2] + direction),
                           weight * (q - NOMINAL_PA)])


def solve_pa_setup(rcm, direction, q0=None, iterations=500, weight=1e-2):
    """Damped least squares for the 7 PA joints: first with a soft pull toward
    :data:`NOMINAL_PA` (picks a posture in the 2-D redundancy), then exact.

    :returns: ``(q, position_error [m], direction_error [rad])``.
    """
    limits = list(saras_arm_joint_limits().values())[:7]
    lo = np.array([lim.lower for lim in limits])
    hi = np.array([lim.upper for lim in limits])
    q = np.array(NOMINAL_PA if q0 is None else q0, dtype=float)
    q = _dls(q, rcm, direction, weight, lo, hi, iterations)
    q = _dls(q, rcm, direction, 0.0, lo, hi, iterations)
    t = saras_arm_rcm_in_base(q)
    pos_err = float(np.linalg.norm(t[:3, 3] - rcm))
    dir_err = float(np.arccos(np.clip(-t[:3, 2] @ direction, -1.0, 1.0)))
    return q, pos_err, dir_err


def _dls(q, rcm, direction, weight, lo, hi, iterations):
    lam = 1e-2
    for _ in range(iterations):
        r = _residual(q, rcm, direction, weight)
        jac = np.empty((r.size, 7))
        for i in range(7):
            dq = np.zeros(7)
            dq[i] = 1e-7
            jac[:, i] = (_residual(q + dq, rcm, direction, weight) - r) / 1e-7
        step = np.linalg.solve(jac.T @ jac + lam * np.eye(7), -jac.T @ r)
        q_new = np.clip(q + step, lo, hi)
        if np.linalg.norm(_residual(q_new, rcm, direction, weight)) < np.linalg.norm(r):
            q, lam = q_new, max(lam / 3.0, 1e-9)
        else:
            lam *= 5.0
        if np.linalg.norm(step) < 1e-13 or lam > 1e6:
            break
    return q
