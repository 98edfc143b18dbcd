"""Adapter between the SARAS arm simulator and the platform's kinematics.

The kinematics of the SARAS arm (passive Positioning Arm -> RCM, Endoscope Robot pivoting about
the RCM, SARAS Adapter) belongs to ``saras_description.kinematics`` (it also generates the URDF,
so the simulator and robot_state_publisher agree). This module does not duplicate that math; it
only wraps it behind the small interface the simulator needs (:class:`DescriptionKinematics`):
``rcm_in_base()``, ``tip_in_rcm(q)``, ``ik_tip(p, roll)``, ``lower``/``upper``, ``joint_names``.

Joint vector used by the simulator and the Socket.IO protocol (6 values, in this order)::

    er_yaw [rad], er_pitch [rad], er_insertion [m], er_roll [rad], adapter_roll [rad], jaw [rad]
"""

import numpy as np

MOTOR_JOINTS = ('er_yaw', 'er_pitch', 'er_insertion', 'er_roll', 'adapter_roll', 'jaw')
PRISMATIC = (False, False, True, False, False, False)
PA_JOINTS = tuple('pa_joint_%d' % i for i in range(1, 8))


class DescriptionKinematics(object):
    """``saras_description.kinematics`` behind the same small interface."""

    source = 'saras_description.kinematics'

    def __init__(self, module, side, pa_joints):
        self.k = module
        self.side = side
        self.pa_joints = np.asarray(pa_joints, dtype=float)
        if self.pa_joints.shape != (7,) or not np.all(np.isfinite(self.pa_joints)):
            raise ValueError('pa_joints must be 7 finite values [rad], got %r' % (pa_joints,))
        self._rcm = np.asarray(module.saras_arm_rcm_in_base(self.pa_joints), dtype=float)
        lim = module.saras_arm_joint_limits()
        self.lower = np.array([lim[n].lower for n in MOTOR_JOINTS], dtype=float)
        self.upper = np.array([lim[n].upper for n in MOTOR_JOINTS], dtype=float)
        self.velocity = np.array([lim[n].velocity for n in MOTOR_JOINTS], dtype=float)

    def joint_names(self, prefix):
        return list(self.k.saras_arm_joint_names(prefix))

    def rcm_in_base(self):
        return self._rcm.copy()

    def tip_in_rcm(self, q):
        return np.asarray(self.k.saras_arm_tip_in_rcm(q), dtype=float)

    def ik_tip(self, p, roll):
        return np.asarray(self.k.saras_arm_ik_tip(p, roll), dtype=float)[:4]


def load(side, pa_joints=None):
    """Kinematics of the ``mesa_<side>`` arm.

    :param pa_joints: the 7 Positioning-Arm set-up joints [rad]; None = the set-up pose of
        ``saras_description/config/saras_arms.yaml`` for this side.
    :raises ValueError: unknown side, or no set-up pose available.
    """
    if side not in ('left', 'right'):
        raise ValueError("side must be 'left' or 'right', got %r" % (side,))
    from saras_description import kinematics as module
    if pa_joints is None:
        from saras_description import config
        try:
            pa_joints = config.load_saras_arms()['mesa_' + side].pa_joints
        except (IOError, OSError, KeyError, ValueError) as e:
            raise ValueError('no Positioning-Arm set-up pose for mesa_%s (%s); set pa_joints' % (side, e))
    return DescriptionKinematics(module, side, pa_joints)
