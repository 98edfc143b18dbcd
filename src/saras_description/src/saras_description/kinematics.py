"""Forward and inverse kinematics of the platform's robots (numpy, no ROS).

Every function here matches the URDF produced by :mod:`saras_description.urdf` (the tests
check it against an independent KDL chain built from the generated XML). Units: metres and
radians; poses are 4x4 homogeneous matrices (``p_parent = T @ p_child``).

Joint naming (what ``sensor_msgs/JointState`` must carry):

* SARAS arms: prefixed, ``mesa_left/pa_joint_1`` ... -- see :func:`saras_arm_joint_names`.
* PSM1/PSM2/ECM: dVRK 1.x names without prefix (``outer_yaw`` ...), as on
  ``/dvrk/<ARM>/state_joint_current``; only the links carry the arm prefix.
* Touch devices: prefixed, ``touch_left/waist`` ... -- see :func:`touch_joint_names`.

Remote-centre (pivot) convention shared by the SARAS Endoscope Robot, PSMs and ECM: the RCM
frame's z axis points out of the patient along the neutral instrument axis, the tool tip is at
negative z. ``yaw`` rotates about -y and ``pitch`` about -x (dVRK), so with the wrist straight
the tip is at ``insertion * (sin(yaw) cos(pitch), -sin(pitch), -cos(yaw) cos(pitch))``.
Tool-tip frames have z along the instrument pointing into the patient.
"""
import math
from collections import OrderedDict

import numpy as np

from saras_description.geometry import EcmGeometry, PsmGeometry, SarasArmGeometry, TouchGeometry
from saras_common.transforms import (quaternion_from_matrix, rot_x, rot_y, rot_z,
                                     transform_from_rpy, translation, wrap_angle)

SARAS_ARM_PREFIXES = ('mesa_left/', 'mesa_right/')
TOUCH_PREFIXES = ('touch_left/', 'touch_right/')
PSM_NAMES = ('PSM1', 'PSM2')

_PA_NAMES = tuple('pa_joint_%d' % i for i in range(1, 8))
_ER_NAMES = ('er_yaw', 'er_pitch', 'er_insertion', 'er_roll', 'adapter_roll', 'jaw')
_PSM_NAMES = ('outer_yaw', 'outer_pitch', 'outer_insertion', 'outer_roll',
              'outer_wrist_pitch', 'outer_wrist_yaw')
_ECM_NAMES = ('outer_yaw', 'outer_pitch', 'insertion', 'outer_roll')
_TOUCH_NAMES = ('waist', 'shoulder', 'elbow', 'yaw', 'pitch', 'roll')


def _vector(values, length, what):
    """Finite float vector of at least ``length`` entries (extra entries are ignored)."""
    q = np.asarray(values, dtype=float).ravel()
    if q.size < length:
        raise ValueError('%s: expected %d joint values, got %d' % (what, length, q.size))
    q = q[:length]
    # math.isfinite over the few floats: 0.5 us instead of 2.9 us for np.all(np.isfinite(q)),
    # whose reduction dispatch was ~7 % of a loaded SARAS arm simulator's active samples (py-spy)
    if not all(map(math.isfinite, q.tolist())):
        raise ValueError('%s: non-finite joint value in %s' % (what, q))
    return q


def _limits(names, table, prefix=''):
    return OrderedDict((prefix + n, table[n]) for n in names)


def within_limits(values, limits, tolerance=1e-9):
    """True if every value lies inside the matching :class:`JointLimit` (same order)."""
    return all(lim.lower - tolerance <= v <= lim.upper + tolerance
               for v, lim in zip(values, limits.values()))


def pivot_tip(yaw, pitch, insertion, roll=0.0):
    """Tool-tip frame in the RCM frame for a straight instrument (shared pivot kinematics).

    :param yaw: rotation about -y of the RCM frame [rad]
    :param pitch: rotation about -x after yaw [rad]
    :param insertion: tip depth below the RCM along the instrument [m]
    :param roll: rotation about the instrument axis [rad]
    :returns: 4x4; z axis along the instrument into the patient.
    """
    # = rot_y(-yaw) @ rot_x(-pitch) @ rot_x(pi) @ translation(z=insertion) @ rot_z(roll), expanded.
    ca, sa = math.cos(yaw), math.sin(yaw)
    cb, sb = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    a0 = (ca, 0.0, sa)                  # columns of rot_y(-yaw) @ rot_x(pi - pitch)
    a1 = (-sa * sb, -cb, ca * sb)
    a2 = (sa * cb, -sb, -ca * cb)
    return np.array([
        [cr * a0[0] + sr * a1[0], cr * a1[0] - sr * a0[0], a2[0], insertion * a2[0]],
        [cr * a0[1] + sr * a1[1], cr * a1[1] - sr * a0[1], a2[1], insertion * a2[1]],
        [cr * a0[2] + sr * a1[2], cr * a1[2] - sr * a0[2], a2[2], insertion * a2[2]],
        [0.0, 0.0, 0.0, 1.0]])


def pivot_ik(position):
    """Inverse of :func:`pivot_tip` for the position: ``(yaw, pitch, insertion)``.

    Unique for tips below the RCM plane (``cos(pitch) > 0``). At the RCM itself the direction
    is undefined and yaw = pitch = 0 is returned.
    """
    p = _vector(position, 3, 'pivot_ik position')
    insertion = float(np.linalg.norm(p))
    if insertion < 1e-12:
        return 0.0, 0.0, 0.0
    d = p / insertion
    pitch = math.asin(max(-1.0, min(1.0, -d[1])))
    yaw = math.atan2(d[0], -d[2])
    return yaw, pitch, insertion


# ------------------------------------------------------------------------------ SARAS arm
def saras_arm_pa_joint_names(prefix):
    """The 7 passive Positioning Arm joints, e.g. ``mesa_left/pa_joint_1``."""
    return [prefix + n for n in _PA_NAMES]


def saras_arm_er_joint_names(prefix):
    """Endoscope Robot + Adapter joints: er_yaw, er_pitch, er_insertion, er_roll, adapter_roll, jaw."""
    return [prefix + n for n in _ER_NAMES]


def saras_arm_joint_names(prefix):
    """All 13 joints of a SARAS arm in JointState order (PA then ER/adapter)."""
    return saras_arm_pa_joint_names(prefix) + saras_arm_er_joint_names(prefix)


def saras_arm_joint_limits(prefix=''):
    """OrderedDict joint name -> :class:`JointLimit`, in :func:`saras_arm_joint_names` order."""
    g = SarasArmGeometry
    out = OrderedDict()
    for name, (axis, _) in zip(_PA_NAMES, g.PA_JOINTS):
        out[prefix + name] = g.PA_LIMIT['revolute_z' if axis[2] else 'revolute_y']
    out.update(_limits(_ER_NAMES, g.ER_LIMITS, prefix))
    return out


def saras_arm_flange_in_base(pa_joints):
    """Positioning-arm flange in ``<p>sbs_world`` for the 7 PA joint values [rad]."""
    q = _vector(pa_joints, 7, 'saras_arm_flange_in_base')
    # t = prod(translation(z=offset_i) @ rot(axis_i, q_i)) @ translation(z=flange), written out with Python
    # floats (columns x, y, z and position p): ~20x faster than 4x4 numpy products.
    x, y, z, p = [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]
    for (axis, offset), qi in zip(SarasArmGeometry.PA_JOINTS, q.tolist()):
        p = [p[i] + offset * z[i] for i in range(3)]
        c, s = math.cos(qi), math.sin(qi)
        if axis[2] == 1.0:    # about z
            x, y = [c * x[i] + s * y[i] for i in range(3)], [c * y[i] - s * x[i] for i in range(3)]
        else:                 # about y
            x, z = [c * x[i] - s * z[i] for i in range(3)], [s * x[i] + c * z[i] for i in range(3)]
    f = SarasArmGeometry.FLANGE_OFFSET
    t = np.eye(4)
    t[:3, 0], t[:3, 1], t[:3, 2] = x, y, z
    t[:3, 3] = [p[i] + f * z[i] for i in range(3)]
    return t


def saras_arm_flange_to_rcm():
    """Fixed transform flange -> ``<p>rcm`` (a copy)."""
    return _FLANGE_TO_RCM.copy()


_FLANGE_TO_RCM = transform_from_rpy(SarasArmGeometry.FLANGE_TO_RCM_XYZ, SarasArmGeometry.FLANGE_TO_RCM_RPY)


def saras_arm_rcm_in_base(pa_joints):
    """``<p>rcm`` (remote centre of motion, the trocar) in ``<p>sbs_world`` (4x4)."""
    return saras_arm_flange_in_base(pa_joints) @ _FLANGE_TO_RCM


def saras_arm_tip_in_rcm(er_adapter_joints):
    """``<p>tool_tip`` in ``<p>rcm`` for [er_yaw, er_pitch, er_insertion, er_roll, adapter_roll(, jaw)].

    The jaw does not move the tip frame. The two rolls are coaxial (redundant): the tip rolls
    by ``er_roll + adapter_roll``.
    """
    q = _vector(er_adapter_joints, 5, 'saras_arm_tip_in_rcm')
    return pivot_tip(q[0], q[1], q[2], q[3] + q[4])


def saras_arm_tip_in_base(joints):
    """``<p>tool_tip`` in ``<p>sbs_world`` for the 13 joints (or 12, without jaw)."""
    q = _vector(joints, 12, 'saras_arm_tip_in_base')
    return saras_arm_rcm_in_base(q[:7]) @ saras_arm_tip_in_rcm(q[7:12])


def saras_arm_ik_tip(tip_position_in_rcm, roll=0.0, er_roll=0.0, jaw=0.0):
    """Endoscope-robot inverse kinematics (pivot about the RCM).

    :param tip_position_in_rcm: desired tool-tip position in ``<p>rcm`` [m]
    :param roll: desired total instrument roll about the shaft [rad]
    :param er_roll: how much of it the Endoscope Robot's roll takes [rad]; the adapter takes
        the rest, wrapped to (-pi, pi]
    :param jaw: jaw opening passed through [rad]
    :returns: numpy array [er_yaw, er_pitch, er_insertion, er_roll, adapter_roll, jaw]. Limits
        are not enforced; check with :func:`within_limits` and :func:`saras_arm_joint_limits`.
    """
    yaw, pitch, insertion = pivot_ik(tip_position_in_rcm)
    if not all(math.isfinite(v) for v in (roll, er_roll, jaw)):
        raise ValueError('saras_arm_ik_tip: non-finite roll/er_roll/jaw')
    return np.array([yaw, pitch, insertion, er_roll, wrap_angle(roll - er_roll), jaw])


# ------------------------------------------------------------------------------ da Vinci PSM
def psm_joint_names():
    """dVRK 1.x PSM joint names (as published on ``/dvrk/PSMx/state_joint_current``)."""
    return list(_PSM_NAMES)


def psm_joint_limits():
    """OrderedDict joint name -> :class:`JointLimit` in :func:`psm_joint_names` order."""
    return _limits(_PSM_NAMES, PsmGeometry.LIMITS)


def psm_tip_in_base(q):
    """``PSMx/tool_tip`` in the ``PSMx`` (RCM) frame for the 6 joints.

    ``outer_insertion`` is the tip depth below the RCM when the wrist is straight.
    """
    q = _vector(q, 6, 'psm_tip_in_base')
    g = PsmGeometry
    wrist = g.WRIST_PITCH_TO_YAW + g.WRIST_YAW_TO_TIP
    return (pivot_tip(q[0], q[1], q[2] - wrist, q[3]) @ rot_x(q[4]) @ translation(z=g.WRIST_PITCH_TO_YAW)
            @ rot_y(q[5]) @ translation(z=g.WRIST_YAW_TO_TIP))


def psm_ik_position(p):
    """First three PSM joints [outer_yaw, outer_pitch, outer_insertion] putting the tool tip at
    ``p`` (PSM base frame, [m]) with the wrist straight (outer_wrist_pitch = outer_wrist_yaw = 0;
    outer_roll then does not move the tip)."""
    return np.array(pivot_ik(p))


# ------------------------------------------------------------------------------ da Vinci ECM
def ecm_joint_names():
    """dVRK 1.x ECM joint names."""
    return list(_ECM_NAMES)


def ecm_joint_limits():
    """OrderedDict joint name -> :class:`JointLimit` in :func:`ecm_joint_names` order."""
    return _limits(_ECM_NAMES, EcmGeometry.LIMITS)


def ecm_tip_in_base(q):
    """``ECM/tool_tip`` (endoscope tip, z along the view direction) in the ``ECM`` frame."""
    q = _vector(q, 4, 'ecm_tip_in_base')
    return pivot_tip(q[0], q[1], q[2], q[3])


def ecm_camera_poses(q, hand_eye):
    """Left and right optical frames in the ``ECM`` frame.

    :param hand_eye: a :class:`saras_description.config.HandEye` (``tip_to_left``,
        ``left_to_right`` 4x4), e.g. from ``config.load_hand_eye()``.
    :returns: ``(T_ecm_left, T_ecm_right)``; optical convention (z forward, x right, y down).
    """
    tip = ecm_tip_in_base(q)
    left = tip @ hand_eye.tip_to_left
    return left, left @ hand_eye.left_to_right


# ------------------------------------------------------------------------------ Touch devices
def touch_joint_names(prefix):
    """Touch joints ``<p>waist, shoulder, elbow, yaw, pitch, roll`` (gimbal = last three)."""
    return [prefix + n for n in _TOUCH_NAMES]


def touch_joint_limits(prefix=''):
    """OrderedDict joint name -> :class:`JointLimit` in :func:`touch_joint_names` order."""
    return _limits(_TOUCH_NAMES, TouchGeometry.LIMITS, prefix)


def touch_elbow_in_base(q):
    """Frame after the elbow joint (origin = elbow axis) in ``<p>base``."""
    g = TouchGeometry
    q = _vector(q, 3, 'touch_elbow_in_base')
    return (rot_z(q[0]) @ translation(z=g.SHOULDER_HEIGHT) @ rot_y(q[1]) @ translation(x=-g.UPPER_ARM)
            @ rot_y(q[2]))


def touch_handle_in_base(q):
    """``<p>handle`` (gimbal centre; x along the Simball shaft away from the user) in ``<p>base``.

    At zero the upper arm points horizontally at the user (-x), the forearm points down and
    the handle frame is aligned with the base frame.
    """
    q = _vector(q, 6, 'touch_handle_in_base')
    return (touch_elbow_in_base(q) @ translation(z=-TouchGeometry.FOREARM) @ rot_z(q[3]) @ rot_y(q[4])
            @ rot_x(q[5]))


def pose_to_position_quaternion(t):
    """(position [m], ROS quaternion (x, y, z, w)) of a 4x4 pose."""
    return np.array(t[:3, 3]), quaternion_from_matrix(t[:3, :3])
