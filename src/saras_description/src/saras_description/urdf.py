"""URDF generators of the platform's robots (xml.etree, no ROS, no xacro).

Each ``*_urdf`` function returns a :class:`Urdf` (call :meth:`Urdf.to_string`). The joint
transforms follow :mod:`saras_description.kinematics` exactly; visuals are simple shapes with
realistic dimensions (:mod:`saras_description.geometry`).

Robots and root links:

* ``saras_arm_urdf('mesa_left/')``: root ``mesa_left/sbs_world``, tip ``mesa_left/tool_tip``.
* ``psm_urdf('PSM1')``: root ``PSM1`` (the RCM), tip ``PSM1/tool_tip``.
* ``ecm_urdf()``: root ``ECM``, tip ``ECM/tool_tip`` and the stereo optical frames.
* ``touch_urdf('touch_left/')``: root ``touch_left/base``, handle ``touch_left/handle``.
* ``platform_urdf()``: everything under ``world``, placed by the world-frames YAML.
"""
import math
import xml.etree.ElementTree as ET

from saras_description import config as cfg
from saras_description.geometry import EcmGeometry, PsmGeometry, SarasArmGeometry, TouchGeometry
from saras_description.kinematics import (ecm_joint_limits, psm_joint_limits,
                                          saras_arm_joint_limits, touch_joint_limits)
from saras_common.transforms import axis_angle, matrix_to_rpy

#: name -> RGBA
MATERIALS = {
    'saras_white': (0.92, 0.92, 0.90, 1.0),
    'saras_blue': (0.15, 0.35, 0.70, 1.0),
    'steel': (0.70, 0.72, 0.75, 1.0),
    'dark': (0.20, 0.20, 0.22, 1.0),
    'davinci_grey': (0.55, 0.57, 0.60, 1.0),
    'davinci_blue': (0.25, 0.45, 0.65, 1.0),
    'touch_grey': (0.35, 0.35, 0.38, 1.0),
    'simball_orange': (0.95, 0.55, 0.10, 1.0),
    'trocar': (0.90, 0.90, 0.95, 0.6),
}


def _fmt(values):
    return ' '.join(repr(round(float(v), 12) + 0.0) for v in values)


class Urdf(object):
    """Minimal URDF document builder (links, joints, simple-shape visuals)."""

    def __init__(self, name):
        self.root = ET.Element('robot', name=name)
        self._materials = set()
        self._links = {}

    # -- elements -------------------------------------------------------------------------
    def _material(self, name):
        if name not in self._materials:
            self._materials.add(name)
            mat = ET.Element('material', name=name)
            ET.SubElement(mat, 'color', rgba=_fmt(MATERIALS[name]))
            self.root.insert(len(self._materials) - 1, mat)

    def link(self, name):
        """Add (or return) link ``name``."""
        if name not in self._links:
            self._links[name] = ET.SubElement(self.root, 'link', name=name)
        return self._links[name]

    def visual(self, link, shape, size, xyz=(0, 0, 0), rpy=(0, 0, 0), material='steel'):
        """Add a visual to ``link``: shape ``box`` (size = x y z [m]), ``cylinder``
        (size = radius, length [m]; along z) or ``sphere`` (size = radius [m])."""
        self._material(material)
        vis = ET.SubElement(self.link(link), 'visual')
        ET.SubElement(vis, 'origin', xyz=_fmt(xyz), rpy=_fmt(rpy))
        geom = ET.SubElement(vis, 'geometry')
        if shape == 'box':
            ET.SubElement(geom, 'box', size=_fmt(size))
        elif shape == 'cylinder':
            ET.SubElement(geom, 'cylinder', radius=_fmt(size[:1]), length=_fmt(size[1:2]))
        elif shape == 'sphere':
            ET.SubElement(geom, 'sphere', radius=_fmt([size]))
        else:
            raise ValueError('unknown shape %r' % shape)
        ET.SubElement(vis, 'material', name=material)

    def rod(self, link, start, end, radius, material='steel'):
        """Cylinder visual from point ``start`` to ``end`` (link frame, [m])."""
        d = [e - s for s, e in zip(start, end)]
        length = math.sqrt(sum(v * v for v in d))
        mid = [(s + e) / 2.0 for s, e in zip(start, end)]
        pitch = math.atan2(math.hypot(d[0], d[1]), d[2])
        yaw = math.atan2(d[1], d[0])
        self.visual(link, 'cylinder', (radius, length), mid, (0.0, pitch, yaw), material)

    def joint(self, name, kind, parent, child, xyz=(0, 0, 0), rpy=(0, 0, 0), axis=None,
              limit=None):
        """Add a joint (``kind`` fixed/revolute/prismatic/continuous); creates the links."""
        self.link(parent)
        self.link(child)
        j = ET.SubElement(self.root, 'joint', name=name, type=kind)
        ET.SubElement(j, 'parent', link=parent)
        ET.SubElement(j, 'child', link=child)
        ET.SubElement(j, 'origin', xyz=_fmt(xyz), rpy=_fmt(rpy))
        if axis is not None:
            ET.SubElement(j, 'axis', xyz=_fmt(axis))
        if limit is not None:
            ET.SubElement(j, 'limit', lower=_fmt([limit.lower]), upper=_fmt([limit.upper]),
                          velocity=_fmt([limit.velocity]), effort=_fmt([limit.effort]))
        return j

    def merge(self, other):
        """Append all links and joints of ``other`` (their names must not clash)."""
        for mat in other.root.findall('material'):
            self._material(mat.get('name'))
        for elem in other.root:
            if elem.tag == 'link':
                name = elem.get('name')
                if name in self._links:  # a frame placed by the host: take over the visuals
                    if len(self._links[name]):
                        raise ValueError('link %s defined twice' % name)
                    self._links[name].extend(list(elem))
                else:
                    self._links[name] = elem
                    self.root.append(elem)
            elif elem.tag == 'joint':
                self.root.append(elem)

    def to_string(self):
        """The URDF as a pretty-printed XML string."""
        tree = ET.ElementTree(self.root)
        ET.indent(tree, space='  ')
        return '<?xml version="1.0"?>\n' + ET.tostring(self.root, encoding='unicode') + '\n'


# ------------------------------------------------------------------------------ SARAS arm
def saras_arm_urdf(prefix, setup=None):
    """SARAS arm (Positioning Arm + Endoscope Robot + SARAS Adapter + instrument).

    :param prefix: e.g. ``'mesa_left/'`` (links and joints are prefixed)
    :param setup: optional :class:`saras_description.config.SarasArmSetup` for the instrument
        shaft size; ``setup.pa_joints`` is *not* baked in (the PA joints stay revolute and are
        read from joint_states) unless :func:`saras_arm_urdf_fixed_pa` is used.
    """
    return _saras_arm(prefix, setup, fixed_pa=False)


def saras_arm_urdf_fixed_pa(prefix, setup):
    """Variant with the passive PA joints frozen (fixed joints) at ``setup.pa_joints``, for a
    driver that does not publish the PA joint values."""
    return _saras_arm(prefix, setup, fixed_pa=True)


def _saras_arm(prefix, setup, fixed_pa):
    g = SarasArmGeometry
    p = prefix
    diameter = setup.shaft_diameter if setup else g.SHAFT_DIAMETER
    shaft = setup.shaft_length if setup else g.SHAFT_LENGTH
    limits = saras_arm_joint_limits(p)
    u = Urdf(p.strip('/') or 'saras_arm')
    base = p + 'sbs_world'
    u.link(base)
    # Rail clamp and column foot.
    u.visual(base, 'box', (0.10, 0.08, 0.10), (0, 0, 0.05), material='dark')
    parent = base
    offsets = [off for _, off in g.PA_JOINTS[1:]] + [g.FLANGE_OFFSET]
    for i, (axis, offset) in enumerate(g.PA_JOINTS):
        name = p + 'pa_joint_%d' % (i + 1)
        child = p + 'pa_link_%d' % (i + 1)
        if fixed_pa:
            # Frozen: origin = offset then rotation about the joint axis by the set-up value.
            rpy = matrix_to_rpy(axis_angle(axis, setup.pa_joints[i])[:3, :3])
            u.joint(name, 'fixed', parent, child, (0, 0, offset), rpy)
        else:
            u.joint(name, 'revolute', parent, child, (0, 0, offset), axis=axis, limit=limits[name])
        radius = 0.04 if i < 2 else 0.032 if i < 5 else 0.028
        u.visual(child, 'sphere', radius * 1.15, material='saras_white')
        u.rod(child, (0, 0, 0), (0, 0, offsets[i]), radius, 'saras_white')
        parent = child
    flange = p + 'flange'
    u.joint(p + 'flange_joint', 'fixed', parent, flange, (0, 0, g.FLANGE_OFFSET))
    u.visual(flange, 'cylinder', (0.04, 0.012), (0, 0, -0.006), material='dark')
    # Endoscope Robot housing: from the flange over to the instrument axis, above the RCM.
    rx, ry, rz = g.FLANGE_TO_RCM_XYZ
    u.visual(flange, 'box', (rx + 0.06, 0.09, 0.07), (rx / 2.0, ry, 0.035), material='saras_blue')
    rcm = p + 'rcm'
    u.joint(p + 'rcm_joint', 'fixed', flange, rcm, g.FLANGE_TO_RCM_XYZ, g.FLANGE_TO_RCM_RPY)
    u.visual(rcm, 'cylinder', (0.0065, 0.04), material='trocar')  # trocar port
    # Pivot mechanism: yaw arc carrier, then the linear axis (pitch link) along the instrument.
    yaw_link, pitch_link = p + 'er_yaw_link', p + 'er_pitch_link'
    u.joint(p + 'er_yaw', 'revolute', rcm, yaw_link, axis=(0, -1, 0), limit=limits[p + 'er_yaw'])
    u.visual(yaw_link, 'box', (0.10, 0.03, 0.04), (0, 0, rz - 0.055), material='saras_blue')
    u.joint(p + 'er_pitch', 'revolute', yaw_link, pitch_link, axis=(-1, 0, 0),
            limit=limits[p + 'er_pitch'])
    u.visual(pitch_link, 'box', (0.03, 0.05, 0.30), (0.0, 0.035, 0.06 + 0.15), material='saras_blue')
    # Insertion: child origin = tool tip (z into the patient), tip depth = joint value.
    ins_link, roll_link, instr = p + 'er_insertion_link', p + 'er_roll_link', p + 'instrument_link'
    u.joint(p + 'er_insertion', 'prismatic', pitch_link, ins_link, rpy=(math.pi, 0, 0),
            axis=(0, 0, 1), limit=limits[p + 'er_insertion'])
    u.visual(ins_link, 'box', (0.03, 0.025, 0.06), (0.0, -0.03, -shaft - 0.03), material='saras_blue')
    u.joint(p + 'er_roll', 'revolute', ins_link, roll_link, axis=(0, 0, 1), limit=limits[p + 'er_roll'])
    # SARAS Adapter housing (rotary + linear part), on the instrument's proximal end.
    u.visual(roll_link, 'box', (0.05, 0.05, 0.11), (0, 0, -shaft - 0.055), material='saras_white')
    u.joint(p + 'adapter_roll', 'revolute', roll_link, instr, axis=(0, 0, 1),
            limit=limits[p + 'adapter_roll'])
    jaw_len = g.JAW_LENGTH
    u.rod(instr, (0, 0, -shaft), (0, 0, -jaw_len), diameter / 2.0, 'steel')
    u.visual(instr, 'box', (diameter * 0.8, diameter / 2.0, jaw_len), (0, -diameter / 4.0, -jaw_len / 2.0),
             material='dark')  # fixed jaw (single-action grasper)
    jaw = p + 'jaw_link'
    u.joint(p + 'jaw', 'revolute', instr, jaw, (0, 0, -jaw_len), axis=(-1, 0, 0), limit=limits[p + 'jaw'])
    u.visual(jaw, 'box', (diameter * 0.8, diameter / 2.0, jaw_len), (0, diameter / 4.0, jaw_len / 2.0),
             material='dark')
    u.joint(p + 'tool_tip_joint', 'fixed', instr, p + 'tool_tip')
    return u


# ------------------------------------------------------------------------------ da Vinci arms
def _rcm_arm_body(u, name, joint_prefix, names, limits, colour):
    """Yaw/pitch links of a da Vinci RCM arm with a simple parallelogram body above the RCM."""
    yaw_link, pitch_link = name + '/outer_yaw_link', name + '/outer_pitch_link'
    u.joint(joint_prefix + names[0], 'revolute', name, yaw_link, axis=(0, -1, 0), limit=limits[names[0]])
    u.visual(yaw_link, 'box', (0.07, 0.09, 0.12), (-0.10, 0.0, 0.60), material=colour)
    u.rod(yaw_link, (0.0, 0.0, 0.55), (-0.10, 0.0, 0.55), 0.02, 'davinci_grey')
    u.joint(joint_prefix + names[1], 'revolute', yaw_link, pitch_link, axis=(-1, 0, 0),
            limit=limits[names[1]])
    u.rod(pitch_link, (-0.05, 0.0, 0.12), (-0.05, 0.0, 0.52), 0.012, 'davinci_grey')
    u.rod(pitch_link, (-0.09, 0.0, 0.14), (-0.09, 0.0, 0.55), 0.012, 'davinci_grey')
    u.visual(pitch_link, 'box', (0.06, 0.04, 0.03), (-0.045, 0.0, 0.12), material=colour)
    return pitch_link


def psm_urdf(name='PSM1', joint_prefix=''):
    """da Vinci PSM stand-in (dVRK 1.x joint names, optionally prefixed for a merged URDF)."""
    g = PsmGeometry
    limits = psm_joint_limits()
    names = list(limits)
    jp = joint_prefix
    u = Urdf(name)
    u.link(name)
    pitch_link = _rcm_arm_body(u, name, jp, names, limits, 'davinci_blue')
    wrist = g.WRIST_PITCH_TO_YAW + g.WRIST_YAW_TO_TIP
    ins, main = name + '/outer_insertion_link', name + '/tool_main_link'
    # Child origin = wrist-pitch axis point, z along the instrument into the patient.
    u.joint(jp + names[2], 'prismatic', pitch_link, ins, (0, 0, 0), (math.pi, 0, 0),
            axis=(0, 0, 1), limit=limits[names[2]])
    # Instrument housing (sterile adapter) on the insertion carriage.
    u.visual(ins, 'box', (0.06, 0.08, 0.09), (-0.03, 0.0, -(wrist + g.SHAFT_LENGTH) - 0.045),
             material='davinci_grey')
    # Wrist point is at (insertion - wrist) below the RCM: shift via a fixed offset link.
    u.joint(jp + names[3], 'revolute', ins, main, (0, 0, -wrist), axis=(0, 0, 1), limit=limits[names[3]])
    u.rod(main, (0, 0, -g.SHAFT_LENGTH), (0, 0, 0), g.SHAFT_DIAMETER / 2.0, 'steel')
    wl, wyl = name + '/tool_wrist_link', name + '/tool_wrist_yaw_link'
    u.joint(jp + names[4], 'revolute', main, wl, axis=(1, 0, 0), limit=limits[names[4]])
    u.visual(wl, 'sphere', g.SHAFT_DIAMETER / 2.0, material='dark')
    u.rod(wl, (0, 0, 0), (0, 0, g.WRIST_PITCH_TO_YAW), g.SHAFT_DIAMETER * 0.4, 'dark')
    u.joint(jp + names[5], 'revolute', wl, wyl, (0, 0, g.WRIST_PITCH_TO_YAW), axis=(0, 1, 0),
            limit=limits[names[5]])
    for side in (-1.0, 1.0):  # closed jaws (the jaw angle is not part of the 6 published joints)
        u.visual(wyl, 'box', (0.0015, 0.004, g.WRIST_YAW_TO_TIP),
                 (side * 0.001, 0, g.WRIST_YAW_TO_TIP / 2.0), material='dark')
    u.joint(jp + 'tool_tip_joint', 'fixed', wyl, name + '/tool_tip', (0, 0, g.WRIST_YAW_TO_TIP))
    return u


def ecm_urdf(hand_eye=None, name='ECM', joint_prefix=''):
    """da Vinci ECM stand-in with the stereo endoscope's optical frames.

    :param hand_eye: :class:`saras_description.config.HandEye` (default: config/ecm_hand_eye.yaml)
    """
    g = EcmGeometry
    hand_eye = hand_eye or cfg.load_hand_eye()
    limits = ecm_joint_limits()
    names = list(limits)
    jp = joint_prefix
    u = Urdf(name)
    u.link(name)
    pitch_link = _rcm_arm_body(u, name, jp, names, limits, 'davinci_grey')
    ins, roll = name + '/insertion_link', name + '/outer_roll_link'
    u.joint(jp + names[2], 'prismatic', pitch_link, ins, (0, 0, 0), (math.pi, 0, 0),
            axis=(0, 0, 1), limit=limits[names[2]])
    u.visual(ins, 'box', (0.07, 0.07, 0.10), (0, 0, -g.SCOPE_LENGTH - 0.05), material='dark')
    u.joint(jp + names[3], 'revolute', ins, roll, axis=(0, 0, 1), limit=limits[names[3]])
    u.rod(roll, (0, 0, -g.SCOPE_LENGTH), (0, 0, 0), g.SCOPE_DIAMETER / 2.0, 'steel')
    tip = name + '/tool_tip'
    u.joint(jp + 'tool_tip_joint', 'fixed', roll, tip)
    for parent, child, t in ((tip, cfg.LEFT_OPTICAL, hand_eye.tip_to_left),
                             (cfg.LEFT_OPTICAL, cfg.RIGHT_OPTICAL, hand_eye.left_to_right)):
        u.joint(child.replace('/', '_') + '_joint', 'fixed', parent, child, t[:3, 3],
                matrix_to_rpy(t[:3, :3]))
    return u


# ------------------------------------------------------------------------------ Touch
def touch_urdf(prefix):
    """Touch haptic device with a Simball handle; prefix e.g. ``'touch_left/'``."""
    g = TouchGeometry
    p = prefix
    limits = touch_joint_limits(p)
    u = Urdf(p.strip('/') or 'touch')
    base = p + 'base'
    u.link(base)
    u.visual(base, 'box', (0.17, 0.16, 0.04), (0.03, 0, 0.02), material='touch_grey')
    links = [p + n for n in ('waist_link', 'upper_arm_link', 'forearm_link', 'gimbal_yaw_link',
                             'gimbal_pitch_link', 'handle')]
    origins = [(0, 0, 0), (0, 0, g.SHOULDER_HEIGHT), (-g.UPPER_ARM, 0, 0), (0, 0, -g.FOREARM),
               (0, 0, 0), (0, 0, 0)]
    axes = [(0, 0, 1), (0, 1, 0), (0, 1, 0), (0, 0, 1), (0, 1, 0), (1, 0, 0)]
    parent = base
    for (name, limit), child, xyz, axis in zip(limits.items(), links, origins, axes):
        u.joint(name, 'revolute', parent, child, xyz, axis=axis, limit=limit)
        parent = child
    u.visual(links[0], 'cylinder', (0.045, g.SHOULDER_HEIGHT - 0.04), (0, 0, 0.04 + (g.SHOULDER_HEIGHT - 0.04) / 2),
             material='touch_grey')
    u.visual(links[1], 'cylinder', (0.03, 0.08), (0, 0, 0), (math.pi / 2, 0, 0), 'dark')
    u.rod(links[1], (0, 0, 0), (-g.UPPER_ARM, 0, 0), 0.011, 'touch_grey')
    u.visual(links[2], 'sphere', 0.014, material='dark')
    u.rod(links[2], (0, 0, 0), (0, 0, -g.FOREARM + 0.02), 0.01, 'touch_grey')
    u.rod(links[3], (0, 0, 0.02), (0, 0, -0.01), 0.008, 'dark')
    u.visual(links[4], 'cylinder', (0.006, 0.05), (0, 0, 0), (math.pi / 2, 0, 0), 'dark')
    # Simball handle: ball joint body, shaft stub pointing away from the user, grip toward the user.
    handle = links[5]
    u.visual(handle, 'sphere', g.SIMBALL_BALL_RADIUS, material='simball_orange')
    u.rod(handle, (0, 0, 0), (0.11, 0, 0), 0.0045, 'steel')
    u.visual(handle, 'box', (0.07, 0.02, 0.03), (-0.055, 0, -0.01), material='dark')
    u.visual(handle, 'cylinder', (0.012, 0.006), (-0.07, 0, -0.04), (math.pi / 2, 0, 0), 'dark')
    return u


# ------------------------------------------------------------------------------ Platform
ROBOTS = ('saras_arm', 'psm', 'ecm', 'touch', 'platform')


def platform_urdf(world_frames_path=None, saras_arms_path=None, hand_eye=None):
    """The complete scene under a ``world`` root (for check_urdf and whole-scene viewers).

    Frames of the world-frames YAML become fixed joints; robots are grafted at their root
    links. Joint names of PSM1/PSM2/ECM get the arm prefix here to stay unique (the per-robot
    URDFs keep the dVRK names).
    """
    world_frames_path = world_frames_path or cfg.default_world_frames_path()
    frames = cfg.load_frames(world_frames_path)
    setups = cfg.load_saras_arms(saras_arms_path)
    u = Urdf('saras_platform')
    u.link('world')
    for f in frames:
        u.joint(f.parent.replace('/', '_') + '_to_' + f.child.replace('/', '_'), 'fixed',
                f.parent, f.child, f.xyz, f.rpy)
    children = {f.child for f in frames}
    robots = []
    for side in ('mesa_left', 'mesa_right'):
        if side not in setups:
            raise cfg.ConfigError('saras_arms config: no set-up for %s' % side)
        robots.append(saras_arm_urdf(side + '/', setups[side]))
    robots += [psm_urdf('PSM1', 'PSM1/'), psm_urdf('PSM2', 'PSM2/'),
               ecm_urdf(hand_eye, 'ECM', 'ECM/'), touch_urdf('touch_left/'), touch_urdf('touch_right/')]
    for robot in robots:
        root = robot.root.find('link').get('name')
        if root not in children:
            raise cfg.ConfigError('%s: no frame places robot root link %s in the world'
                                  % (world_frames_path, root))
        u.merge(robot)  # the root link's visuals move onto the placement frame's link
    return u
