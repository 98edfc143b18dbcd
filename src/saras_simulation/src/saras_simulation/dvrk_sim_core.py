"""The whole simulated da Vinci at time ``t``: surgeon script -> MTMs -> teleoperation -> PSMs, the
ECM, the foot pedals, each arm under its CRTK core (client commands take an arm over). ROS-agnostic
core of dvrk_sim.

Per tick (:meth:`ConsoleSim.step`): the surgeon script gives the MTM handle poses and the pedal
states; each MTM's joints track its pose (one damped-least-squares step); each PSM's goal is the
teleoperation of its MTM's *actual* pose (scripted or moved by a client), its joints track it; the
jaw follows the MTM gripper; the ECM follows its viewpoint script. :class:`crtk_arm.CrtkArm`
decides whether the script or a client drives each arm.

Units: metres, radians, seconds.
"""
import math

import numpy as np

from saras_common import params as prm
from saras_simulation import crtk_arm, dvrk_console, dvrk_kinematics, dvrk_motion

MTM_JOINT_NAMES = dvrk_kinematics.MTM_JOINT_NAMES
PEDALS = dvrk_console.PEDALS
PSM_JAW_OPEN = 0.6      # [rad] jaw opening of the scripted surgeon (needle release)

#: dvrk_sim's own parameters (config/dvrk_sim.yaml; saras_common.params spec); the psm / ecm /
#: console / crtk_arms sections are validated by :class:`ConsoleSim`.
NODE_PARAMS = {
    'rate': (100.0, prm.in_range(1.0, 1000.0), 'Hz', 'publication rate of poses and joint states'),
    'max_catch_up': (30, prm.in_range(1, 1000, integral=True), 'samples',
                     'published at once after a late wake-up; older ones are skipped'),
    'publish_queue_size': (0, prm.non_negative_integer, 'messages',
                           'rospy publisher queue (0 = synchronous publish)'),
    'bag': ('', prm.text, '', "rosbag to replay instead of the script ('' = scripted motion)"),
    'loop': (True, prm.boolean, '', 'replay: restart at the end of the bag'),
    'crtk': (False, prm.boolean, '', 'also serve the dVRK 2.x CRTK interface'),
    'crtk_ns': ('/', prm.Rule('absolute namespace', lambda v: isinstance(v, str) and v.startswith('/')),
                '', 'CRTK namespace'),
    'crtk_aux_rate': (10.0, prm.non_negative, 'Hz', 'jacobians and wrenches (0 = every sample)'),
    'publish_tf': (False, prm.boolean, '', 'arm tips and optical frames on /tf (standalone use)'),
    'frames_file': ('', prm.text, '', "world_frames YAML of the arm bases ('' = none)"),
    'publish_link_tf': (False, prm.boolean, '', "the arms' URDF joint TF"),
    'link_tf_rate': (50.0, prm.non_negative, 'Hz', 'publish_link_tf rate (0 = every sample)'),
    'robot_description_param': ('/{arm}/robot_description',
                                prm.Rule("text containing '{arm}'",
                                         lambda v: isinstance(v, str) and '{arm}' in v),
                                '', 'URDF parameter of each arm for publish_link_tf'),
}


def _limits(kind):
    from saras_description.geometry import EcmGeometry, PsmGeometry
    if kind == 'PSM':
        names, table = dvrk_motion.PSM_JOINT_NAMES, PsmGeometry.LIMITS
    else:
        names, table = dvrk_motion.ECM_JOINT_NAMES, EcmGeometry.LIMITS
    lim = dvrk_kinematics.limits_of(table, names)
    vel = np.array([table[n].velocity for n in names])
    return lim, vel


class ConsoleSim(object):
    """Five arms (PSM1, PSM2, ECM, MTML, MTMR) and the foot pedals. ``cfg`` is the dvrk_sim.yaml
    dictionary (``psm``, ``ecm``, ``console``, ``crtk`` sections); raises ValueError naming a bad key."""

    def __init__(self, cfg, kinematics=None):
        self.base = dvrk_motion.DvrkSimCore.from_config(cfg, kinematics)
        self.kin = self.base.kin
        con = dict(cfg.get('console') or {})
        crtk = dict(cfg.get('crtk_arms') or {})
        try:
            scale = float(con.get('scale', 0.2))
            mtm_of = {p: m for p, m in dict(con.get('mtm_of', {'PSM1': 'MTMR', 'PSM2': 'MTML'})).items()
                      if p in self.base.psm_motions}
            centre = dict(con.get('mtm_centre', {'MTML': [0.12, 0.28, -0.36],
                                                 'MTMR': [-0.12, 0.28, -0.36]}))
            reg = {p: dvrk_console.registration_from_rpy(con.get('registration', {}).get(p, [0, 0, 0]))
                   for p in mtm_of}
            timeout = float(crtk.get('client_timeout', 5.0))
            rejoin = float(crtk.get('rejoin_time', 2.0))
            accel = float(crtk.get('joint_acceleration', 2.0))
        except (TypeError, ValueError, AttributeError) as ex:
            raise ValueError('parameter console / crtk_arms invalid: %s' % ex)
        if set(mtm_of) != set(self.base.psm_motions) or len(set(mtm_of.values())) != len(mtm_of) \
                or not set(mtm_of.values()) <= {'MTML', 'MTMR'}:
            raise ValueError('parameter console/mtm_of must map %s onto MTML / MTMR (one each)'
                             % sorted(self.base.psm_motions))
        self.mtm_of = mtm_of
        self.teleop = {p: dvrk_console.Teleop(scale, reg[p]) for p in mtm_of}
        self.chains = {}
        lim, vel = _limits('PSM')
        for p in self.base.psm_motions:
            self.chains[p] = dvrk_kinematics.psm_chain(lim)
        ecm_lim, ecm_vel = _limits('ECM')
        self.chains['ECM'] = dvrk_kinematics.ecm_chain(ecm_lim)
        for m in mtm_of.values():
            self.chains[m] = dvrk_kinematics.mtm_chain()
        try:
            self.script = dvrk_console.SurgeonScript(
                self.base.psm_motions, mtm_of, centre, self.kin.psm_tip_in_base, scale,
                ecm_moving=self._ecm_moving, **_script_args(con))
        except (TypeError, KeyError) as ex:
            raise ValueError('parameter console invalid: %s' % ex)
        self.script.maps = {p: dvrk_console.Teleop(scale, reg[p]) for p in mtm_of}  # per-PSM registration
        self.pedals = dvrk_console.PedalEvents()
        q_psm, _, T_mtm, _ = self.script.sample(0.0, self.kin)
        self.arms = {}
        for p, q in q_psm.items():
            self.arms[p] = crtk_arm.CrtkArm(p, self.chains[p], q, vel, accel * vel,
                                            jaw=crtk_arm.jaw_group(), client_timeout=timeout,
                                            rejoin_time=rejoin)
        q_ecm = self.base.ecm_motion.joints(0.0) if self.base.ecm_motion else [0.0, 0.0, 0.1, 0.0]
        self.arms['ECM'] = crtk_arm.CrtkArm('ECM', self.chains['ECM'], q_ecm, ecm_vel,
                                            accel * ecm_vel, client_timeout=timeout, rejoin_time=rejoin)
        self.mtm_q = {}
        for m, T in T_mtm.items():
            q, residual = self.chains[m].ik(T, np.zeros(7), max_iter=100)
            if residual > 1e-4:
                raise ValueError('parameter console/mtm_centre: %s handle pose unreachable '
                                 '(residual %.3g)' % (m, residual))
            self.mtm_q[m] = q
            self.arms[m] = crtk_arm.CrtkArm(m, self.chains[m], q, 1.5, 1.5 * accel,
                                            jaw=crtk_arm.jaw_group(limits=(0.0, 1.0)),
                                            client_timeout=timeout, rejoin_time=rejoin)
        self.psm_q = dict(q_psm)
        self.poses = {}

    def _ecm_moving(self, t):
        e = self.base.ecm_motion
        if e is None or len(e.poses) < 2:
            return False
        seg = e.dwell + e.move_time
        return (t % seg) >= e.dwell

    def jaw_script(self, psm, tau):
        """Scripted jaw [rad]: opens once per stitch (needle release during the return phase)."""
        m = self.base.psm_motions[psm]
        s = (tau / m.period + m.phase) % 1.0
        return PSM_JAW_OPEN * 0.5 * (1.0 - math.cos(2.0 * math.pi * s))

    def step(self, t):
        """Advance to ``t`` [s]. Returns ({arm: (q, jaw or None, T_base_tip)}, {pedal: pressed} for
        the pedals that changed, {arm: [operating-state events]})."""
        q_intent, _, T_mtm, pedals = self.script.sample(t, self.kin)
        tau = self.script.task_time(t)[0]
        out = {}
        for psm, mtm in self.mtm_of.items():
            self.mtm_q[mtm] = self.chains[mtm].track(T_mtm[mtm], self.mtm_q[mtm])
            q, grip = self.arms[mtm].step(t, self.mtm_q[mtm], [self.jaw_script(psm, tau)])
            out[mtm] = (q, grip, self.chains[mtm].fk(q))
        for psm, mtm in self.mtm_of.items():
            now = self.poses.get(psm)
            if now is None:
                now = self.chains[psm].fk(self.arms[psm].joints.q)
            goal = self.teleop[psm].update(out[mtm][2], pedals['clutch'], now)
            if not pedals['clutch']:
                self.psm_q[psm] = self.chains[psm].track(goal, self.psm_q[psm])
            q, jaw = self.arms[psm].step(t, self.psm_q[psm], out[mtm][1])
            out[psm] = (q, jaw, self.chains[psm].fk(q))
            self.poses[psm] = out[psm][2]
        script_ecm = self.base.ecm_motion.joints(t) if self.base.ecm_motion else None
        q, _ = self.arms['ECM'].step(t, script_ecm)
        out['ECM'] = (q, None, self.chains['ECM'].fk(q))
        events = {a: arm.pop_events() for a, arm in self.arms.items()}
        return out, self.pedals.update(pedals), events


def _script_args(con):
    keys = ('clutch_period', 'clutch_duration', 'clutch_phase', 'clutch_offset', 'coag_period',
            'coag_duration', 'operator_present_after')
    return {k: con[k] for k in keys if k in con}
