"""Joint transforms of a URDF (what robot_state_publisher computes), ROS-agnostic.

Used by ``saras_arms_state`` (``~publish_tf``) to broadcast a SARAS arm's TF itself, one
TFMessage per state sample: robot_state_publisher subscribes to ``joint_states`` with a queue of
one, so on a loaded host it keeps only the newest of the samples that arrived while it was not
scheduled and the arm's TF rate falls far below the state rate.

Supported joint types: ``revolute``, ``continuous``, ``prismatic`` (one axis) and ``fixed``;
``mimic`` joints follow ``multiplier * q + offset``. Units: m, rad. Quaternions [x, y, z, w].
"""

import math
import xml.etree.ElementTree as ET

import numpy as np
from saras_common.transforms import axis_angle, quaternion_from_matrix, rpy_to_matrix, translation

MOVING = ('revolute', 'continuous', 'prismatic')


def _quat_mul(a, b):
    """Hamilton product of two quaternions (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


class Joint(object):
    """One URDF joint: ``origin`` (4x4, parent -> joint frame at q = 0), unit ``axis``."""

    def __init__(self, name, jtype, parent, child, origin, axis, mimic=None):
        self.name, self.type, self.parent, self.child = name, jtype, parent, child
        self.origin = origin
        self.axis = axis
        self.mimic = mimic          # (joint name, multiplier, offset) or None
        # plain-float copies for :meth:`xyz_quat` (per sample; numpy's per-call overhead on 3-
        # and 4-vectors is most of the cost there)
        self._t = tuple(float(x) for x in origin[:3, 3])
        self._r = tuple(tuple(float(x) for x in row) for row in origin[:3, :3])
        self._q = tuple(float(x) for x in quaternion_from_matrix(origin))
        self._axis = tuple(float(x) for x in axis)

    def xyz_quat(self, q):
        """parent -> child at joint position q [rad or m] as (xyz, quaternion x y z w with w >= 0),
        the same transform as :meth:`transform` (composed as quaternions, no matrices)."""
        if self.type == 'prismatic':
            d = tuple(a * q for a in self._axis)
            t = self._t
            return (tuple(t[i] + r[0] * d[0] + r[1] * d[1] + r[2] * d[2] for i, r in enumerate(self._r)),
                    self._q)
        if self.type == 'fixed':
            return self._t, self._q
        s = math.sin(0.5 * q)
        ax, ay, az = self._axis
        x, y, z, w = _quat_mul(self._q, (ax * s, ay * s, az * s, math.cos(0.5 * q)))
        n = math.sqrt(x * x + y * y + z * z + w * w)
        if w < 0.0:
            n = -n
        return self._t, (x / n, y / n, z / n, w / n)

    def transform(self, q):
        """parent -> child [4x4] at joint position q [rad or m]."""
        if self.type == 'fixed':
            return self.origin
        m = translation(*(self.axis * q)) if self.type == 'prismatic' else axis_angle(self.axis, q)
        return self.origin.dot(m)


class UrdfTf(object):
    """Transforms of the joints of a URDF string.

    :meth:`moving` -> ``[(parent, child, xyz, xyzw)]`` of the movable joints for a joint vector
    (in the order of ``joint_names``); :meth:`fixed` -> the same for the fixed joints.
    :raises ValueError: unparsable URDF, a joint type other than those supported, or a joint of
        ``joint_names`` that the URDF does not have.
    """

    def __init__(self, urdf_xml, joint_names):
        try:
            root = ET.fromstring(urdf_xml)
        except ET.ParseError as e:
            raise ValueError('robot_description is not valid XML: %s' % e)
        self.joints = []
        for j in root.findall('joint'):
            jtype = j.get('type')
            if jtype not in MOVING + ('fixed',):
                raise ValueError('joint %s: unsupported type %r' % (j.get('name'), jtype))
            o = j.find('origin')
            xyz = [float(x) for x in (o.get('xyz', '0 0 0') if o is not None else '0 0 0').split()]
            rpy = [float(x) for x in (o.get('rpy', '0 0 0') if o is not None else '0 0 0').split()]
            origin = np.eye(4)
            origin[:3, :3] = rpy_to_matrix(rpy)
            origin[:3, 3] = xyz
            a = j.find('axis')
            axis = np.array([float(x) for x in (a.get('xyz') if a is not None else '1 0 0').split()])
            if jtype != 'fixed':
                n = np.linalg.norm(axis)
                if not n > 0.0:
                    raise ValueError('joint %s: zero axis' % j.get('name'))
                axis = axis / n
            mm = j.find('mimic')
            mimic = None
            if mm is not None:
                mimic = (mm.get('joint'), float(mm.get('multiplier', 1.0)), float(mm.get('offset', 0.0)))
            self.joints.append(Joint(j.get('name'), jtype, j.find('parent').get('link'),
                                     j.find('child').get('link'), origin, axis, mimic))
        self.joint_names = list(joint_names)
        self._index = {n: i for i, n in enumerate(self.joint_names)}
        self.movable = [j for j in self.joints if j.type in MOVING]
        self._cache = [None] * len(self.movable)
        for j in self.movable:
            src = j.mimic[0] if j.mimic else j.name
            if src not in self._index:
                raise ValueError('URDF joint %s is not in the published joint list' % src)

    def _q(self, joint, q):
        if joint.mimic:
            name, mult, off = joint.mimic
            return mult * q[self._index[name]] + off
        return q[self._index[joint.name]]

    def moving(self, q):
        """Transforms of the movable joints; a joint whose position did not change since the
        previous call reuses its result (the passive arm joints are constant)."""
        out = []
        for k, j in enumerate(self.movable):
            v = self._q(j, q)
            c = self._cache[k]
            if c is None or c[0] != v:
                c = (v, (j.parent, j.child) + j.xyz_quat(v))
                self._cache[k] = c
            out.append(c[1])
        return out

    def fixed(self):
        return [(j.parent, j.child, j.origin[:3, 3], quaternion_from_matrix(j.origin))
                for j in self.joints if j.type == 'fixed']

    def chain(self, q, root, tip):
        """root -> tip [4x4] by composing the joint transforms (tests, diagnostics)."""
        by_child = {j.child: j for j in self.joints}
        m = np.eye(4)
        link = tip
        while link != root:
            if link not in by_child:
                raise ValueError('%s is not below %s' % (tip, root))
            j = by_child[link]
            m = (j.transform(self._q(j, q)) if j.type != 'fixed' else j.origin).dot(m)
            link = j.parent
        return m
