"""Test helpers: an INDEPENDENT forward kinematics of a URDF file, built with PyKDL.

The XML is parsed here (xml.etree) and every joint becomes a KDL segment the way kdl_parser
does it (joint origin with the axis rotated into the parent frame; rpy via KDL's own
Rotation.RPY), so nothing of saras_description's kinematics or transform code is used.
"""
import xml.etree.ElementTree as ET

import numpy as np
import PyKDL as kdl


def _floats(text, default):
    return [float(v) for v in text.split()] if text else default


class UrdfTree(object):
    """Joints of a URDF document, indexed by child link."""

    def __init__(self, xml_text):
        self.root = ET.fromstring(xml_text)
        self.joints = {}
        for j in self.root.findall('joint'):
            origin = j.find('origin')
            axis = j.find('axis')
            self.joints[j.find('child').get('link')] = {
                'name': j.get('name'), 'type': j.get('type'), 'parent': j.find('parent').get('link'),
                'xyz': _floats(origin.get('xyz') if origin is not None else None, [0.0] * 3),
                'rpy': _floats(origin.get('rpy') if origin is not None else None, [0.0] * 3),
                'axis': _floats(axis.get('xyz') if axis is not None else None, [1.0, 0.0, 0.0]),
                'limit': j.find('limit'),
            }
        self.links = [link.get('name') for link in self.root.findall('link')]

    def chain(self, root, tip):
        """KDL chain root -> tip and the names of its movable joints (root to tip order)."""
        path = []
        link = tip
        while link != root:
            if link not in self.joints:
                raise KeyError('%s is not below %s' % (tip, root))
            path.append(self.joints[link])
            link = self.joints[link]['parent']
        chain = kdl.Chain()
        names = []
        for j in reversed(path):
            origin = kdl.Frame(kdl.Rotation.RPY(*j['rpy']), kdl.Vector(*j['xyz']))
            axis = origin.M * kdl.Vector(*j['axis'])
            if j['type'] in ('revolute', 'continuous'):
                joint = kdl.Joint(j['name'], origin.p, axis, kdl.Joint.RotAxis)
                names.append(j['name'])
            elif j['type'] == 'prismatic':
                joint = kdl.Joint(j['name'], origin.p, axis, kdl.Joint.TransAxis)
                names.append(j['name'])
            else:
                joint = kdl.Joint(j['name'], kdl.Joint.Fixed)
            chain.addSegment(kdl.Segment(j['name'], joint, origin))
        return chain, names

    def fk(self, root, tip, values):
        """4x4 pose of ``tip`` in ``root`` for the joint values ``{name: value}``."""
        chain, names = self.chain(root, tip)
        q = kdl.JntArray(len(names))
        for i, n in enumerate(names):
            q[i] = values[n]
        frame = kdl.Frame()
        kdl.ChainFkSolverPos_recursive(chain).JntToCart(q, frame)
        out = np.eye(4)
        for r in range(3):
            for c in range(3):
                out[r, c] = frame.M[r, c]
            out[r, 3] = frame.p[r]
        return out
