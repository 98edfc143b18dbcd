"""Loading and validation of the package's YAML files (PyYAML, no ROS).

Every loader raises :class:`ConfigError` (a ``ValueError``) whose message names the file and
the offending key, so command-line tools and nodes can exit with a clear message.
"""
import math
import os
from collections import namedtuple

import numpy as np
import yaml

from saras_description import frames as frames_mod
from saras_common.transforms import transform_from_rpy

#: ECM camera extrinsics: ``tip_to_left`` (ECM/tool_tip -> endoscope/left_optical_frame) and
#: ``left_to_right`` (left -> right optical frame), 4x4 each; the source frames too.
HandEye = namedtuple('HandEye', 'tip_to_left left_to_right frames')
#: SARAS arm set-up: 7 Positioning-Arm joint values [rad] and instrument shaft size [m].
SarasArmSetup = namedtuple('SarasArmSetup', 'pa_joints shaft_diameter shaft_length')

ECM_TIP = 'ECM/tool_tip'
LEFT_OPTICAL = 'endoscope/left_optical_frame'
RIGHT_OPTICAL = 'endoscope/right_optical_frame'


class ConfigError(ValueError):
    """A configuration file is missing, malformed or holds an invalid value."""


def package_dir():
    """The package's share directory (source tree, or install share via rospkg)."""
    here = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
    if os.path.isfile(os.path.join(here, 'package.xml')):
        return here
    try:  # installed: the module lives in dist-packages, the data in share/
        import rospkg  # pylint: disable=import-outside-toplevel
        return rospkg.RosPack().get_path('saras_description')
    except Exception as exc:  # noqa: BLE001 -- any failure means: not found
        raise ConfigError('cannot locate the saras_description package: %s' % exc)


def default_path(name):
    """Path of ``config/<name>`` in this package."""
    return os.path.join(package_dir(), 'config', name)


def default_world_frames_path():
    """saras_bringup's ``config/world_frames.yaml`` (sibling source package, or via rospkg)."""
    sibling = os.path.join(os.path.dirname(package_dir()), 'saras_bringup', 'config',
                           'world_frames.yaml')
    if os.path.isfile(sibling):
        return sibling
    try:
        import rospkg  # pylint: disable=import-outside-toplevel
        return os.path.join(rospkg.RosPack().get_path('saras_bringup'), 'config',
                            'world_frames.yaml')
    except Exception as exc:  # noqa: BLE001
        raise ConfigError('cannot locate saras_bringup/config/world_frames.yaml: %s' % exc)


def _load(path):
    try:
        with open(path) as f:
            data = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError('%s: cannot read YAML: %s' % (path, exc))
    if not isinstance(data, dict):
        raise ConfigError('%s: expected a mapping at the top level' % path)
    return data


def _numbers(value, n, where):
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise ConfigError('%s: expected a list of %d numbers, got %r' % (where, n, value))
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError):
        raise ConfigError('%s: expected numbers, got %r' % (where, value))
    if not all(math.isfinite(v) for v in out):
        raise ConfigError('%s: non-finite value in %r' % (where, value))
    return out


def load_frames(path):
    """Frames of a frames-format YAML (``frames: [{parent, child, xyz, rpy|quaternion}, ...]``).

    Parsed by :mod:`saras_description.frames` (the platform's one parser of the format) without
    requiring a ``world`` root (the hand-eye file is a stand-alone chain). Entries carry
    ``parent``, ``child``, ``xyz`` [m] and ``rpy`` [rad].
    """
    try:
        return frames_mod.load_frames(path, root=None)
    except frames_mod.FramesError as exc:
        raise ConfigError(str(exc))


def load_hand_eye(path=None):
    """ECM camera extrinsics from ``config/ecm_hand_eye.yaml`` (frames format).

    Required entries: ``ECM/tool_tip -> endoscope/left_optical_frame`` and
    ``endoscope/left_optical_frame -> endoscope/right_optical_frame``.
    """
    path = path or default_path('ecm_hand_eye.yaml')
    frames = load_frames(path)
    found = {(f.parent, f.child): f for f in frames}
    out = []
    for key in ((ECM_TIP, LEFT_OPTICAL), (LEFT_OPTICAL, RIGHT_OPTICAL)):
        if key not in found:
            raise ConfigError('%s: missing frame entry {parent: %s, child: %s}' % (path, key[0], key[1]))
        out.append(found[key])
    baseline = np.linalg.norm(out[1].xyz)
    if not 0.001 <= baseline <= 0.02:
        raise ConfigError('%s: stereo baseline %.4f m (left->right xyz) outside [0.001, 0.02] m'
                          % (path, baseline))
    if np.linalg.norm(out[0].xyz) > 0.05:
        raise ConfigError('%s: tool_tip->left camera offset %.3f m is implausible (> 0.05 m)'
                          % (path, np.linalg.norm(out[0].xyz)))
    return HandEye(transform_from_rpy(out[0].xyz, out[0].rpy), transform_from_rpy(out[1].xyz, out[1].rpy), out)


def load_saras_arms(path=None):
    """Per-arm set-up from ``config/saras_arms.yaml``: dict ``{'mesa_left': SarasArmSetup, ...}``."""
    # Imported here to avoid a cycle (kinematics does not need the config).
    from saras_description.kinematics import saras_arm_joint_limits  # pylint: disable=import-outside-toplevel
    path = path or default_path('saras_arms.yaml')
    data = _load(path)
    arms = data.get('arms')
    if not isinstance(arms, dict) or not arms:
        raise ConfigError('%s: "arms" must map arm names (mesa_left, ...) to set-ups' % path)
    out = {}
    for name, arm in arms.items():
        where = '%s: arms.%s' % (path, name)
        if not isinstance(arm, dict):
            raise ConfigError('%s: expected a mapping' % where)
        pa = _numbers(arm.get('pa_joints'), 7, where + '.pa_joints')
        limits = list(saras_arm_joint_limits().items())[:7]
        for (jname, lim), v in zip(limits, pa):
            if not lim.lower <= v <= lim.upper:
                raise ConfigError('%s.pa_joints: %s = %.4f rad outside [%.4f, %.4f]'
                                  % (where, jname, v, lim.lower, lim.upper))
        diameter = float(arm.get('shaft_diameter', 0.005))
        if not 0.002 <= diameter <= 0.012:
            raise ConfigError('%s.shaft_diameter: %r m outside [0.002, 0.012] (5 mm or 10 mm '
                              'laparoscopic instruments)' % (where, diameter))
        length = float(arm.get('shaft_length', 0.36))
        if not 0.2 <= length <= 0.5:
            raise ConfigError('%s.shaft_length: %r m outside [0.2, 0.5]' % (where, length))
        out[name] = SarasArmSetup(np.array(pa), diameter, length)
    return out
