"""Joint values of a slow demonstration motion of every robot (for display.launch; numpy only).

The SARAS arms stay in their set-up pose (config/saras_arms.yaml) with the instrument tip in
the abdomen; the PSMs point at the surgical site; the ECM looks at it; the Touch handles sway.
All values are kept inside the joint limits.
"""
import math

import numpy as np

from saras_description import kinematics as k

#: PSM tool-tip targets in the PSM base frames [m] (the site, seen from world_frames.yaml bases).
PSM_TARGETS = {'PSM1': (-0.08, 0.06, -0.12), 'PSM2': (-0.08, -0.06, -0.12)}
#: ECM viewing direction in the ECM frame (toward the site) and insertion [m].
ECM_TARGET = (-0.14, 0.0, -0.14)
ECM_INSERTION = 0.05


def _clip(values, limits):
    lo = np.array([lim.lower for lim in limits.values()])
    hi = np.array([lim.upper for lim in limits.values()])
    return np.clip(values, lo, hi)


class DemoMotion(object):
    """Produces ``(topic, joint names, positions)`` for every robot at time ``t`` [s]."""

    def __init__(self, saras_setups, dvrk_ns='/dvrk'):
        """:param saras_setups: ``config.load_saras_arms()`` result (needs mesa_left/right)."""
        self._saras = [(side, saras_setups[side].pa_joints) for side in ('mesa_left', 'mesa_right')]
        self._dvrk_ns = dvrk_ns.rstrip('/')
        self._psm = {name: k.psm_ik_position(p) for name, p in PSM_TARGETS.items()}
        d = np.array(ECM_TARGET) / np.linalg.norm(ECM_TARGET)
        self._ecm = np.array(k.pivot_ik(d * ECM_INSERTION))

    def joint_states(self, t, animate=True):
        """List of ``(topic, names, positions)``; ``animate=False`` gives the rest pose."""
        a = 1.0 if animate else 0.0
        s = math.sin
        out = []
        for i, (side, pa) in enumerate(self._saras):
            prefix = side + '/'
            ph = 1.3 * i
            er = [0.12 * a * s(0.5 * t + ph), 0.10 * a * s(0.7 * t + ph), 0.13 + 0.02 * a * s(0.3 * t + ph),
                  0.0, 0.6 * a * s(0.4 * t + ph), 0.4 + 0.3 * a * s(1.0 * t + ph)]
            q = _clip(np.concatenate([pa, er]), k.saras_arm_joint_limits(prefix))
            out.append(('/%s/joint_states' % side, k.saras_arm_joint_names(prefix), q))
        for i, (name, q3) in enumerate(sorted(self._psm.items())):
            ph = 0.9 * i
            q = np.array([q3[0] + 0.10 * a * s(0.6 * t + ph), q3[1] + 0.08 * a * s(0.8 * t + ph),
                          q3[2] + 0.02 * a * s(0.5 * t + ph), 0.8 * a * s(0.4 * t + ph),
                          0.5 * a * s(0.9 * t + ph), 0.5 * a * s(1.1 * t + ph)])
            out.append(('%s/%s/state_joint_current' % (self._dvrk_ns, name), k.psm_joint_names(),
                        _clip(q, k.psm_joint_limits())))
        q = self._ecm.tolist() + [0.0]
        q[0] += 0.05 * a * s(0.2 * t)
        out.append(('%s/ECM/state_joint_current' % self._dvrk_ns, k.ecm_joint_names(),
                    _clip(np.array(q), k.ecm_joint_limits())))
        for i, side in enumerate(('touch_left', 'touch_right')):
            ph = 0.7 * i
            q = np.array([0.25 * a * s(0.5 * t + ph), 0.35 + 0.15 * a * s(0.6 * t + ph),
                          0.30 + 0.15 * a * s(0.7 * t + ph), 0.4 * a * s(0.5 * t + ph),
                          0.3 * a * s(0.6 * t + ph), 0.8 * a * s(0.3 * t + ph)])
            out.append(('/%s/joint_states' % side, k.touch_joint_names(side + '/'),
                        _clip(q, k.touch_joint_limits(side + '/'))))
        return out
