"""Core of the ``global_frame_registration`` node: every robot base in one world frame.

Arms touch the dots of the circular pattern with their tool tip (forward kinematics gives the
tip in the arm base); the endoscope sees the ArUco markers (pattern pose in the camera), and the
ECM kinematics plus the hand-eye transform bring that pose into the ECM base. Each robot
thus knows ``T_base_pattern``; with the pattern placed at ``T_world_pattern`` (default: printed
side up at the world origin, so the world frame is the pattern frame turned z-up),
``T_world_base = T_world_pattern @ inv(T_base_pattern)``.
"""
from collections import OrderedDict

import numpy as np

from .pattern import CircularPattern
from .registration import RegistrationError, register_points
from saras_common.transforms import average_rotation, inverse, make_transform, transform_from_rpy, validate_transform
from .world_frames import frame_entry

__all__ = ['GlobalRegistration', 'DEFAULT_PATTERN_IN_WORLD']

#: Pattern lying printed side up on the table at the world origin, dot 0 along world x
#: (the pattern frame has z into the board, so it is the world frame rotated by pi about x).
DEFAULT_PATTERN_IN_WORLD = transform_from_rpy([0.0, 0.0, 0.0], [np.pi, 0.0, 0.0])


class GlobalRegistration:
    """Collects touches and endoscope observations, computes the world frames.

    :param pattern: :class:`CircularPattern` geometry.
    :param T_world_pattern: 4x4 pose of the pattern in the world [m].
    :param world_frame: name of the world frame.
    :param max_rms: a registration whose touch residual RMS exceeds this [m] is rejected
        (a dot touched wrongly or the wrong dot index).
    """

    def __init__(self, pattern=None, T_world_pattern=None, world_frame='world', max_rms=0.002):
        self.pattern = pattern or CircularPattern()
        self.T_world_pattern = (DEFAULT_PATTERN_IN_WORLD.copy() if T_world_pattern is None
                                else validate_transform(T_world_pattern, 'T_world_pattern'))
        self.world_frame = world_frame
        self.max_rms = float(max_rms)
        self.touches = OrderedDict()      # base frame -> {dot index: tip position in base}
        self.views = OrderedDict()        # base frame -> [T_base_pattern from the endoscope]

    def add_touch(self, base_frame, dot_index, tip_in_base):
        """Record the tool-tip position [m, arm base frame] touching dot ``dot_index``."""
        if not 0 <= int(dot_index) < self.pattern.n_dots:
            raise RegistrationError('dot index %r outside [0, %d)' % (dot_index, self.pattern.n_dots))
        p = np.asarray(tip_in_base, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise RegistrationError('tool-tip position for %s must be 3 finite numbers, got %r' % (base_frame, tip_in_base))
        self.touches.setdefault(base_frame, OrderedDict())[int(dot_index)] = p

    def remove_touch(self, base_frame, dot_index):
        self.touches.get(base_frame, {}).pop(int(dot_index), None)

    def add_endoscope_view(self, base_frame, T_base_ee, T_ee_cam, T_cam_pattern):
        """Record one endoscope observation: ECM end effector in its base (kinematics), hand-eye
        ``T_ee_cam`` and the detected ``T_cam_pattern``."""
        T = (validate_transform(T_base_ee, 'T_base_ee') @ validate_transform(T_ee_cam, 'T_ee_cam')
             @ validate_transform(T_cam_pattern, 'T_cam_pattern'))
        self.views.setdefault(base_frame, []).append(T)

    def base_in_pattern(self):
        """Dict base frame -> (4x4 ``T_base_pattern``, rms [m] or None, number of samples)."""
        out = OrderedDict()
        for base, touches in self.touches.items():
            if len(touches) < 3:
                continue
            idx = list(touches)
            T, rms = register_points(np.array([touches[i] for i in idx]), self.pattern.dot_positions()[idx])
            if rms > self.max_rms:
                raise RegistrationError('%s: touched dots do not fit the pattern (rms %.2f mm > %.2f mm); '
                                        'check the dot order and touch again' % (base, rms * 1e3, self.max_rms * 1e3))
            out[base] = (T, rms, len(idx))
        for base, views in self.views.items():
            Ts = np.array(views)
            T = make_transform(average_rotation(Ts[:, :3, :3]), Ts[:, :3, 3].mean(axis=0))
            spread = float(np.sqrt(np.mean(np.sum((Ts[:, :3, 3] - T[:3, 3]) ** 2, axis=1)))) if len(Ts) > 1 else None
            out[base] = (T, spread, len(Ts))
        return out

    def missing(self, required):
        """Bases of ``required`` that cannot be computed yet."""
        have = set(b for b, t in self.touches.items() if len(t) >= 3) | set(self.views)
        return [b for b in required if b not in have]

    def world_transforms(self):
        """Dict base frame -> 4x4 ``T_world_base``."""
        return OrderedDict((b, self.T_world_pattern @ inverse(T)) for b, (T, _, _) in self.base_in_pattern().items())

    def entries(self):
        """World-frame YAML entries (``world -> base``)."""
        return [frame_entry(self.world_frame, b, T) for b, T in self.world_transforms().items()]
