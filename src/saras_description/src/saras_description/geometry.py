"""Dimensions and joint limits of every robot of the platform, as plain data.

Both the URDF generator (:mod:`saras_description.urdf`) and the kinematics
(:mod:`saras_description.kinematics`) read these values, so a change here changes both.
Units: metres, radians, m/s or rad/s, N or N m. Values are realistic approximations
(simple geometric shapes; no vendor CAD data is used).
"""
import math
from collections import namedtuple

#: A joint's limits. ``kind`` is ``'revolute'`` or ``'prismatic'``; lower/upper [rad] or [m];
#: velocity [rad/s] or [m/s]; effort [N m] or [N].
JointLimit = namedtuple('JointLimit', 'kind lower upper velocity effort')


def _deg(d):
    return math.radians(d)


# --------------------------------------------------------------------------------------------
# SARAS arm = passive Positioning Arm (PA, 7 revolute joints, braked) + Endoscope Robot (ER, 4
# motors pivoting the instrument about the remote centre of motion) + SARAS Adapter (instrument
# roll, jaw) + laparoscopic instrument (Karl Storz Click Line 5 mm class).
# --------------------------------------------------------------------------------------------
class SarasArmGeometry(object):
    """SARAS arm dimensions. Frames: see README (``sbs_world`` z up, PA straight up at zero)."""

    #: PA joints: (axis of the joint in its own frame, offset [m] of the joint frame from the
    #: previous joint frame along the previous z). Axes alternate z, y (S-R-S 7-DOF layout);
    #: only z and y axes are supported by kinematics.saras_arm_flange_in_base.
    PA_JOINTS = (
        ((0.0, 0.0, 1.0), 0.10),   # pa_joint_1: column rotation, 10 cm above the rail clamp
        ((0.0, 1.0, 0.0), 0.22),   # pa_joint_2: shoulder
        ((0.0, 0.0, 1.0), 0.12),   # pa_joint_3: upper-arm rotation
        ((0.0, 1.0, 0.0), 0.12),   # pa_joint_4: elbow (upper arm 0.24 m)
        ((0.0, 0.0, 1.0), 0.11),   # pa_joint_5: forearm rotation
        ((0.0, 1.0, 0.0), 0.11),   # pa_joint_6: wrist (forearm 0.22 m)
        ((0.0, 0.0, 1.0), 0.05),   # pa_joint_7: flange rotation
    )
    #: pa_joint_7 frame -> flange (mechatronic interface of the Endoscope Robot) [m].
    FLANGE_OFFSET = 0.04
    #: flange -> RCM: the Endoscope Robot's remote centre lies beside and below its mount.
    #: xyz [m], rpy [rad]. The rpy flips z so that the rcm frame's z axis points out of the
    #: patient along the neutral instrument axis (dVRK convention: tool tip at negative z).
    FLANGE_TO_RCM_XYZ = (0.09, 0.0, 0.24)
    FLANGE_TO_RCM_RPY = (math.pi, 0.0, 0.0)

    PA_LIMIT = {  # passive, braked joints (velocity/effort are nominal)
        'revolute_z': JointLimit('revolute', _deg(-170.0), _deg(170.0), 1.0, 50.0),
        'revolute_y': JointLimit('revolute', _deg(-125.0), _deg(125.0), 1.0, 50.0),
    }
    ER_LIMITS = {
        'er_yaw': JointLimit('revolute', _deg(-45.0), _deg(45.0), 1.0, 5.0),
        'er_pitch': JointLimit('revolute', _deg(-45.0), _deg(45.0), 1.0, 5.0),
        'er_insertion': JointLimit('prismatic', 0.0, 0.25, 0.10, 20.0),
        'er_roll': JointLimit('revolute', -math.pi, math.pi, 2.0, 1.0),
        'adapter_roll': JointLimit('revolute', -math.pi, math.pi, 3.0, 0.5),
        'jaw': JointLimit('revolute', 0.0, _deg(60.0), 2.0, 0.5),
    }
    #: Instrument: shaft diameter and length (tip to adapter) [m]; single-action jaw length [m].
    SHAFT_DIAMETER = 0.005
    SHAFT_LENGTH = 0.36
    JAW_LENGTH = 0.018


# --------------------------------------------------------------------------------------------
# da Vinci stand-ins (dVRK 1.x joint names). Base frame = RCM; the tool tip is at negative z.
# --------------------------------------------------------------------------------------------
class PsmGeometry(object):
    """Patient Side Manipulator with an EndoWrist-like needle driver."""

    WRIST_PITCH_TO_YAW = 0.0091   # [m] (dVRK large needle driver)
    WRIST_YAW_TO_TIP = 0.0102     # [m]
    SHAFT_DIAMETER = 0.0085       # [m]
    SHAFT_LENGTH = 0.4162         # [m] wrist to instrument housing
    LIMITS = {
        'outer_yaw': JointLimit('revolute', _deg(-91.0), _deg(91.0), 1.5, 20.0),
        'outer_pitch': JointLimit('revolute', _deg(-53.0), _deg(53.0), 1.5, 20.0),
        'outer_insertion': JointLimit('prismatic', 0.0, 0.24, 0.2, 50.0),
        'outer_roll': JointLimit('revolute', _deg(-260.0), _deg(260.0), 3.0, 1.0),
        'outer_wrist_pitch': JointLimit('revolute', _deg(-80.0), _deg(80.0), 3.0, 1.0),
        'outer_wrist_yaw': JointLimit('revolute', _deg(-80.0), _deg(80.0), 3.0, 1.0),
    }


class EcmGeometry(object):
    """Endoscope Camera Manipulator with a 0 degree stereo endoscope."""

    SCOPE_DIAMETER = 0.012        # [m]
    SCOPE_LENGTH = 0.40           # [m] tip to camera head
    LIMITS = {
        'outer_yaw': JointLimit('revolute', _deg(-80.0), _deg(80.0), 1.0, 20.0),
        'outer_pitch': JointLimit('revolute', _deg(-45.0), _deg(65.0), 1.0, 20.0),
        'insertion': JointLimit('prismatic', 0.0, 0.23, 0.1, 50.0),
        'outer_roll': JointLimit('revolute', _deg(-90.0), _deg(90.0), 1.0, 5.0),
    }


# --------------------------------------------------------------------------------------------
# Touch haptic device (3 actuated arm joints + 3-DOF passive gimbal) carrying a Simball handle.
# --------------------------------------------------------------------------------------------
class TouchGeometry(object):
    """Approximate 3D Systems Touch dimensions; base z up, x away from the user, y left."""

    SHOULDER_HEIGHT = 0.15        # [m] waist axis origin to the shoulder axis
    UPPER_ARM = 0.1325            # [m] shoulder axis to elbow axis
    FOREARM = 0.1325              # [m] elbow axis to gimbal centre (= handle frame)
    LIMITS = {
        'waist': JointLimit('revolute', _deg(-60.0), _deg(60.0), 5.0, 1.0),
        'shoulder': JointLimit('revolute', _deg(-10.0), _deg(100.0), 5.0, 1.0),
        'elbow': JointLimit('revolute', _deg(-60.0), _deg(70.0), 5.0, 1.0),
        'yaw': JointLimit('revolute', _deg(-150.0), _deg(150.0), 10.0, 0.1),
        'pitch': JointLimit('revolute', _deg(-80.0), _deg(80.0), 10.0, 0.1),
        'roll': JointLimit('revolute', _deg(-150.0), _deg(150.0), 10.0, 0.1),
    }
    SIMBALL_BALL_RADIUS = 0.022   # [m]
