"""Serial-chain kinematics of the simulated da Vinci arms (PSM, ECM, MTM), ROS-agnostic.

* :class:`Chain`: a serial chain of fixed transforms and 1-DOF joints (rotation about or translation
  along x, y or z, with a sign and an offset), its forward kinematics, its geometric Jacobian and a
  damped-least-squares inverse kinematics (:meth:`Chain.ik`). One forward pass gives the pose and
  the Jacobian, so the CRTK ``servo_cp``/``move_cp`` and the teleoperation cost one pass per
  iteration.
* :func:`psm_chain`, :func:`ecm_chain`: the PSM and ECM of ``saras_description.kinematics`` (the URDF
  model robot_state_publisher uses) written as chains; the tests check both against it.
* :func:`mtm_chain`: a stand-in master tool manipulator with the dVRK 1.x MTM joint names (outer yaw,
  shoulder and elbow pitch, a four-joint gimbal). Its link lengths are those of the da Vinci MTM
  (upper arm 0.279 m, forearm 0.365 m); the gimbal is idealised (intersecting axes).

Units: metres, radians. Poses are 4x4 numpy arrays in the arm's base frame.
"""
import math

import numpy as np

_AXES = {'x': 0, 'y': 1, 'z': 2}
_OTHER = ((1, 2), (2, 0), (0, 1))   # the two other axes of x, y, z, in right-handed order

#: dVRK 1.x MTM joint names (state_joint_current / measured_js of MTML, MTMR).
MTM_JOINT_NAMES = ('outer_yaw', 'shoulder_pitch', 'elbow_pitch', 'wrist_platform', 'wrist_pitch',
                   'wrist_yaw', 'wrist_roll')
MTM_UPPER_ARM = 0.2794      # [m] shoulder pitch to elbow pitch (da Vinci MTM)
MTM_FOREARM = 0.3645        # [m] elbow pitch to the gimbal centre (da Vinci MTM)


def _rot(axis, a):
    c, s = math.cos(a), math.sin(a)
    i = _AXES[axis]
    j, k = (i + 1) % 3, (i + 2) % 3
    R = np.eye(4)
    R[j, j], R[j, k], R[k, j], R[k, k] = c, -s, s, c
    return R


def _trans(axis, d):
    T = np.eye(4)
    T[_AXES[axis], 3] = d
    return T


def fixed_rot(axis, a):
    """Chain element: a fixed rotation of ``a`` [rad] about ``axis``."""
    return ('fixed', _rot(axis, a))


def fixed_trans(axis, d):
    """Chain element: a fixed translation of ``d`` [m] along ``axis``."""
    return ('fixed', _trans(axis, d))


def revolute(axis, sign=1.0, offset=0.0):
    """Chain element: rotation of ``sign * q + offset`` about ``axis``."""
    return ('r', axis, float(sign), float(offset))


def prismatic(axis, sign=1.0, offset=0.0):
    """Chain element: translation of ``sign * q + offset`` along ``axis``."""
    return ('p', axis, float(sign), float(offset))


def _compose(cols, p, fcols, fp):
    """(R, p) @ (Rf, pf) with rotations as lists of 3 columns: (R Rf, p + R pf)."""
    x, y, z = cols
    out = [[x[0] * f[0] + y[0] * f[1] + z[0] * f[2], x[1] * f[0] + y[1] * f[1] + z[1] * f[2],
            x[2] * f[0] + y[2] * f[1] + z[2] * f[2]] for f in fcols]
    return out, [p[0] + x[0] * fp[0] + y[0] * fp[1] + z[0] * fp[2],
                 p[1] + x[1] * fp[0] + y[1] * fp[1] + z[1] * fp[2],
                 p[2] + x[2] * fp[0] + y[2] * fp[1] + z[2] * fp[2]]


def pose_error(T, goal, orientation_weight=1.0):
    """6-vector (position [m], weighted rotation vector [rad]) from ``T`` to ``goal`` (base frame)."""
    t, g = T[:3].tolist(), goal[:3].tolist()
    # Rerr = Rgoal Rt^T: Rerr[i][j] = row i of Rgoal . row j of Rt
    r = [[g[i][0] * t[j][0] + g[i][1] * t[j][1] + g[i][2] * t[j][2] for j in range(3)] for i in range(3)]
    c = max(-1.0, min(1.0, (r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0))
    angle = math.acos(c)
    v = (r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1])
    if angle < 1e-9:
        f = 0.5
    elif math.pi - angle < 1e-6:
        # half-turn: axis from the symmetric part
        k = max(range(3), key=lambda i: r[i][i])
        n = math.sqrt(2.0 * (1.0 + r[k][k]))
        v = tuple(r[i][k] + (1.0 if i == k else 0.0) for i in range(3))
        f = angle / n
    else:
        f = angle / (2.0 * math.sin(angle))
    f *= orientation_weight
    return np.array([g[0][3] - t[0][3], g[1][3] - t[1][3], g[2][3] - t[2][3], f * v[0], f * v[1], f * v[2]])


class Chain(object):
    """Serial chain: ``elements`` from :func:`fixed_rot`, :func:`fixed_trans`, :func:`revolute`,
    :func:`prismatic`, base to tip; ``limits`` optional ``[(lower, upper)]`` per joint (IK clamps)."""

    def __init__(self, elements, limits=None, orientation_weight=1.0):
        self.elements = list(elements)
        self.n = sum(1 for e in self.elements if e[0] != 'fixed')
        self.limits = None if limits is None else np.asarray(limits, dtype=float)
        if self.limits is not None and self.limits.shape != (self.n, 2):
            raise ValueError('Chain: limits must be %d (lower, upper) pairs' % self.n)
        self.orientation_weight = float(orientation_weight)
        self._compiled = [('fixed', [list(e[1][:3, c]) for c in range(3)], list(e[1][:3, 3]))
                          if e[0] == 'fixed' else (e[0], _AXES[e[1]], e[2], e[3]) for e in self.elements]
        self._weights = np.array([1.0, 1.0, 1.0] + [self.orientation_weight] * 3)

    def fk(self, q, jacobian=False):
        """Tip pose (4x4); with ``jacobian`` also the 6 x n geometric Jacobian (linear; angular),
        in the base frame (the dVRK's spatial Jacobian convention).

        Computed on Python floats (rotation columns and position as lists), one numpy array built
        at the end: for these 4-7 joint chains, numpy's per-call overhead on 3-vectors costs
        several times the arithmetic."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.n,):
            raise ValueError('Chain.fk: %d joint values expected, got %s' % (self.n, q.shape))
        q = q.tolist()
        cols = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]   # rotation columns x, y, z
        p = [0.0, 0.0, 0.0]
        joints = [] if jacobian else None
        i = 0
        for e in self._compiled:
            if e[0] == 'fixed':
                cols, p = _compose(cols, p, e[1], e[2])
                continue
            kind, a, sign, offset = e
            v = sign * q[i] + offset
            i += 1
            ca = cols[a]
            if jacobian:
                joints.append((kind, (ca[0] * sign, ca[1] * sign, ca[2] * sign), tuple(p)))
            if kind == 'r':      # post-multiplied rotation about axis a: mixes the two other columns
                j, k = _OTHER[a]
                c, s = math.cos(v), math.sin(v)
                cj, ck = cols[j], cols[k]
                cols = list(cols)
                cols[j] = [c * cj[0] + s * ck[0], c * cj[1] + s * ck[1], c * cj[2] + s * ck[2]]
                cols[k] = [c * ck[0] - s * cj[0], c * ck[1] - s * cj[1], c * ck[2] - s * cj[2]]
            else:                # post-multiplied translation along axis a
                p = [p[0] + v * ca[0], p[1] + v * ca[1], p[2] + v * ca[2]]
        x, y, z = cols
        T = np.array([[x[0], y[0], z[0], p[0]], [x[1], y[1], z[1], p[1]], [x[2], y[2], z[2], p[2]],
                      [0.0, 0.0, 0.0, 1.0]])
        if not jacobian:
            return T
        rows = [[0.0] * self.n for _ in range(6)]
        for k, (kind, a, o) in enumerate(joints):
            if kind == 'r':      # linear: a x (tip - joint origin); angular: a
                d0, d1, d2 = p[0] - o[0], p[1] - o[1], p[2] - o[2]
                rows[0][k], rows[1][k], rows[2][k] = a[1] * d2 - a[2] * d1, a[2] * d0 - a[0] * d2, \
                    a[0] * d1 - a[1] * d0
                rows[3][k], rows[4][k], rows[5][k] = a
            else:
                rows[0][k], rows[1][k], rows[2][k] = a
        return T, np.array(rows)

    def clamp(self, q):
        if self.limits is None:
            return q
        return np.minimum(np.maximum(q, self.limits[:, 0]), self.limits[:, 1])

    def ik(self, goal, q0, tol=1e-6, max_iter=30, damping=1e-4):
        """Joint values reaching ``goal`` (4x4) from the reference ``q0`` (damped least squares,
        within the limits). Returns ``(q, residual)``; residual = norm of the remaining weighted
        pose error (m / rad)."""
        q = self.clamp(np.array(q0, dtype=float))
        W = self._weights
        err = None
        for _ in range(max_iter):
            T, J = self.fk(q, jacobian=True)
            err = pose_error(T, goal, self.orientation_weight)
            if np.linalg.norm(err) < tol:
                break
            Jw = J * W[:, None]
            dq = Jw.T @ np.linalg.solve(Jw @ Jw.T + damping * np.eye(6), err)
            q = self.clamp(q + dq)
        else:
            err = pose_error(self.fk(q), goal, self.orientation_weight)
        return q, float(np.linalg.norm(err))

    def track(self, goal, q, damping=1e-4):
        """One damped-least-squares step from ``q`` towards ``goal``: the per-tick update of a
        smoothly moving goal (second-order error), at the cost of one forward pass."""
        q = np.asarray(q, dtype=float)
        T, J = self.fk(q, jacobian=True)
        err = pose_error(T, goal, self.orientation_weight)
        Jw = J * self._weights[:, None]
        A = Jw @ Jw.T
        A[np.diag_indices(6)] += damping
        return self.clamp(q + Jw.T @ np.linalg.solve(A, err))


def psm_chain(limits=None):
    """PSM tool tip in the PSM base (RCM) frame, joints ``outer_yaw .. outer_wrist_yaw`` (= the URDF's
    ``saras_description.kinematics.psm_tip_in_base``)."""
    from saras_description.geometry import PsmGeometry as g
    return Chain([revolute('y', -1.0), revolute('x', -1.0), fixed_rot('x', math.pi),
                  prismatic('z', 1.0, -(g.WRIST_PITCH_TO_YAW + g.WRIST_YAW_TO_TIP)),
                  revolute('z'), revolute('x'), fixed_trans('z', g.WRIST_PITCH_TO_YAW),
                  revolute('y'), fixed_trans('z', g.WRIST_YAW_TO_TIP)], limits)


def ecm_chain(limits=None):
    """ECM camera tip in the ECM base (RCM) frame, 4 joints (= ``kinematics.ecm_tip_in_base``).
    Four joints cannot hold a 6-D goal: the IK reaches the position and keeps what it can of the
    orientation (orientation weight 0.001, i.e. 1 rad counts as 1 mm)."""
    return Chain([revolute('y', -1.0), revolute('x', -1.0), fixed_rot('x', math.pi),
                  prismatic('z'), revolute('z')], limits, orientation_weight=0.001)


def mtm_chain():
    """Stand-in MTM: handle frame in the MTM base frame (z up, y towards the surgeon). At zero joints
    the upper arm points along +y, the forearm down and the handle's z axis down (the
    instrument direction it commands)."""
    return Chain([revolute('z'), revolute('x'), fixed_trans('y', MTM_UPPER_ARM),
                  revolute('x'), fixed_trans('z', -MTM_FOREARM),
                  revolute('z'), revolute('x'), revolute('y'), fixed_rot('x', math.pi),
                  revolute('z')])


def limits_of(table, names):
    """``[(lower, upper)]`` in ``names`` order from a saras_description LIMITS table."""
    return [(table[n].lower, table[n].upper) for n in names]


def twist(T_prev, T, dt):
    """Cartesian velocity (linear m/s, angular rad/s; base frame) from two poses ``dt`` [s] apart."""
    if not dt > 0:
        return np.zeros(6)
    return pose_error(T_prev, T) / dt
