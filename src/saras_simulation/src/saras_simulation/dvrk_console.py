"""The simulated da Vinci master console: surgeon script, MTM -> PSM teleoperation, foot pedals.
ROS-agnostic.

* :class:`Teleop`: the dVRK's PSM teleoperation: the PSM tip follows the MTM handle's translation
  scaled by ``scale`` (rotated by ``registration``, MTM base -> PSM base) and its rotation (relative
  to the orientations at engagement). While the clutch is pressed the PSM holds and the MTM moves
  freely; on release both are re-anchored, so the PSM does not jump.
* :class:`SurgeonScript`: the main surgeon's hands. The intent is the suturing motion of each PSM
  (:class:`saras_simulation.dvrk_motion.SuturingMotion`); the script turns it into MTM handle poses
  the teleoperation maps back onto that motion. Every ``clutch_period`` seconds the surgeon presses
  the clutch for ``clutch_duration`` seconds and re-centres the hands by ``clutch_offset`` (the
  intent pauses meanwhile, the PSMs hold); the camera pedal is pressed while the ECM moves; coag
  is tapped every ``coag_period`` seconds; the head sensor reports the operator from
  ``operator_present_after`` seconds on.
* :class:`PedalEvents`: edge detection: a pedal's event is published only when its state changes,
  as the dVRK does (``sensor_msgs/Joy`` with ``buttons[0]`` 1 = pressed, 0 = released).

Units: metres, radians, seconds. Poses are 4x4 numpy arrays.
"""
import math

import numpy as np

from saras_common import transforms
from saras_simulation.dvrk_motion import smoothstep

#: Pedal / button names, dVRK spelling (topic suffixes under footpedals/).
PEDALS = ('clutch', 'camera', 'coag', 'operatorpresent')


class Teleop(object):
    """MTM -> PSM cartesian mapping with clutch (dVRK ``mtsTeleOperationPSM`` behaviour)."""

    def __init__(self, scale=0.2, registration=None):
        if not 0.0 < scale <= 1.0:
            raise ValueError('teleop scale must be in (0, 1], got %r' % (scale,))
        self.scale = float(scale)
        self.R = np.eye(3) if registration is None else np.asarray(registration, dtype=float)
        self.anchor = None      # (mtm pose, psm pose) at engagement
        self.clutched = False

    def engage(self, mtm, psm):
        """(Re-)anchor at the current MTM and PSM poses."""
        self.anchor = (np.array(mtm, dtype=float), np.array(psm, dtype=float))

    def update(self, mtm, clutch, psm_now):
        """PSM goal pose for the MTM pose ``mtm``; ``psm_now`` is the PSM's current pose (held while
        ``clutch`` is pressed, and the new anchor on release)."""
        if clutch:
            self.clutched = True
            return np.array(psm_now, dtype=float)
        if self.clutched or self.anchor is None:
            self.clutched = False
            self.engage(mtm, psm_now)
        m0, p0 = self.anchor
        goal = np.eye(4)
        goal[:3, 3] = p0[:3, 3] + self.scale * (self.R @ (mtm[:3, 3] - m0[:3, 3]))
        # relative rotation of the handle since engagement, expressed in the PSM base
        dR = self.R @ (mtm[:3, :3] @ m0[:3, :3].T) @ self.R.T
        goal[:3, :3] = dR @ p0[:3, :3]
        return goal

    def inverse(self, psm_goal):
        """MTM pose that makes :meth:`update` (engaged) return ``psm_goal``."""
        m0, p0 = self.anchor
        T = np.eye(4)
        T[:3, 3] = m0[:3, 3] + self.R.T @ (psm_goal[:3, 3] - p0[:3, 3]) / self.scale
        dR = self.R.T @ (psm_goal[:3, :3] @ p0[:3, :3].T) @ self.R
        T[:3, :3] = dR @ m0[:3, :3]
        return T


def _windows(t, period, duration, phase):
    """(index, fraction) of the window of ``duration`` every ``period`` s containing ``t`` (shifted
    by ``phase`` s), or (number of windows started, None) outside one."""
    if period <= 0 or duration <= 0:
        return 0, None
    x = t - phase
    if x < 0:
        return 0, None
    k = int(math.floor(x / period))
    s = x - k * period
    if s < duration:
        return k, s / duration
    return k + 1, None


class SurgeonScript(object):
    """Scripted surgeon at the master console (see the module docstring).

    ``psm_motions``: {PSM name: SuturingMotion}; ``mtm_of``: {PSM name: MTM name} (dVRK default
    MTMR -> PSM1, MTML -> PSM2); ``mtm_centre``: {MTM name: handle position [m] at the start, MTM
    base frame}; ``ecm_moving``: callable t -> bool (ECM between viewpoints)."""

    def __init__(self, psm_motions, mtm_of, mtm_centre, psm_fk, scale=0.2, registration=None,
                 clutch_period=24.0,
                 clutch_duration=1.5, clutch_phase=6.0, clutch_offset=(0.0, 0.0, 0.03),
                 coag_period=16.0, coag_duration=0.4, operator_present_after=0.5,
                 ecm_moving=None):
        if clutch_period > 0 and not 0 < clutch_duration < clutch_period:
            raise ValueError('clutch_duration must be in (0, clutch_period)')
        self.psm_motions = dict(psm_motions)
        self.mtm_of = dict(mtm_of)
        self.psm_fk = psm_fk
        # the hands' own map (anchored once, never clutched): the live Teleop re-anchors at each
        # clutch release with the offset already in the MTM pose, so PSM = intent again
        self.maps = {psm: Teleop(scale, registration) for psm in self.psm_motions}
        self.clutch = (float(clutch_period), float(clutch_duration), float(clutch_phase))
        self.offset = np.asarray(clutch_offset, dtype=float)
        self.coag = (float(coag_period), float(coag_duration))
        self.operator_after = float(operator_present_after)
        self.ecm_moving = ecm_moving or (lambda t: False)
        self.mtm_start = {}
        for psm, mtm in self.mtm_of.items():
            T = np.eye(4)
            T[:3, 3] = np.asarray(mtm_centre[mtm], dtype=float)
            self.mtm_start[psm] = T

    def task_time(self, t):
        """Time of the surgeon's intent: real time minus the time spent clutching; and the clutch
        state (index of the clutch window, fraction of it or None)."""
        period, duration, phase = self.clutch
        k, frac = _windows(t, period, duration, phase)
        spent = k * duration if frac is None else k * duration + frac * duration
        return t - spent, k, frac

    def hand_offset(self, k, frac):
        """Re-centring offset of the hands [m, MTM frame]: alternates 0 / offset at each clutch."""
        before = self.offset if k % 2 == 1 else np.zeros(3)
        if frac is None:
            return before
        after = self.offset if (k + 1) % 2 == 1 else np.zeros(3)
        return before + smoothstep(frac) * (after - before)

    def sample(self, t, kin_ik):
        """Script at ``t``: ({PSM: intent joints}, {PSM: intent pose}, {MTM: handle pose},
        {pedal: pressed}). ``kin_ik(p)`` is the PSM position IK (SuturingMotion.joints argument)."""
        tau, k, frac = self.task_time(t)
        offset = self.hand_offset(k, frac)
        q_psm, T_psm, T_mtm = {}, {}, {}
        for psm, motion in self.psm_motions.items():
            q = motion.joints(tau, kin_ik)
            T = self.psm_fk(q)
            hands = self.maps[psm]
            if hands.anchor is None:
                hands.engage(self.mtm_start[psm] @ _rot_like(T), T)
            M = hands.inverse(T)
            M[:3, 3] += offset
            q_psm[psm], T_psm[psm], T_mtm[self.mtm_of[psm]] = q, T, M
        pedals = {
            'clutch': frac is not None,
            'camera': bool(self.ecm_moving(t)),
            'coag': _windows(t, self.coag[0], self.coag[1], self.coag[0] / 2.0)[1] is not None,
            'operatorpresent': t >= self.operator_after,
        }
        return q_psm, T_psm, T_mtm, pedals


def _rot_like(T):
    """Rotation part of ``T`` only (as a 4x4): the handle starts oriented like the instrument."""
    R = np.eye(4)
    R[:3, :3] = T[:3, :3]
    return R


class PedalEvents(object):
    """Edge detector: :meth:`update` returns the pedals whose state changed ({name: pressed})."""

    def __init__(self, names=PEDALS):
        self.state = {n: None for n in names}

    def update(self, pressed):
        out = {}
        for n, v in pressed.items():
            if n in self.state and self.state[n] != bool(v):
                self.state[n] = bool(v)
                out[n] = bool(v)
        return out


def registration_from_rpy(rpy):
    """3x3 rotation MTM base -> PSM base from roll, pitch, yaw [rad] (config helper)."""
    if len(rpy) != 3 or not all(math.isfinite(float(v)) for v in rpy):
        raise ValueError('registration must be 3 finite angles [rad], got %r' % (rpy,))
    return transforms.rpy_to_matrix([float(v) for v in rpy])
