"""Static world frames of the platform: parsing and validation of world_frames.yaml.

The file format (shared with saras_calibration, which writes it)::

    frames:
      - {parent: world, child: PSM1, xyz: [0.10, -0.08, 0.22], rpy: [0.0, 0.0, 0.0]}

``xyz`` in metres, ``rpy`` in radians (fixed axes: roll about x, pitch about y, yaw about z,
i.e. R = Rz(yaw) Ry(pitch) Rx(roll), the URDF / tf convention). A ``quaternion: [x, y, z, w]``
may be given instead of ``rpy``. No ROS import here: the node ``scripts/world_frames`` adapts it.
"""
import math

import numpy as np
import yaml
from saras_description import transforms  # the platform's one implementation of rotations


class FramesError(ValueError):
    """A world-frames file that cannot be used; the message names the entry and the field."""


class StaticFrame(object):
    """One static transform parent -> child (translation [m], unit quaternion x, y, z, w)."""

    __slots__ = ('parent', 'child', 'translation', 'quaternion')

    def __init__(self, parent, child, translation, quaternion):
        self.parent = parent
        self.child = child
        self.translation = tuple(float(v) for v in translation)
        self.quaternion = tuple(float(v) for v in quaternion)

    def matrix(self):
        """4x4 homogeneous transform T_parent_child."""
        T = np.eye(4)
        T[:3, :3] = quaternion_to_matrix(self.quaternion)
        T[:3, 3] = self.translation
        return T

    def __repr__(self):
        return 'StaticFrame(%s -> %s, t=%s, q=%s)' % (self.parent, self.child,
                                                       self.translation, self.quaternion)


def rpy_to_quaternion(roll, pitch, yaw):
    """Fixed-axis roll/pitch/yaw [rad] to a unit quaternion (x, y, z, w), w >= 0."""
    return tuple(float(v) for v in transforms.matrix_to_quat(transforms.rpy_to_matrix([roll, pitch, yaw])))


def quaternion_to_matrix(q):
    """Unit quaternion (x, y, z, w) to a 3x3 rotation matrix."""
    return transforms.quat_to_matrix(q)


def _vector(entry, index, key, length):
    value = entry.get(key)
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise FramesError('frames[%d] (%s): "%s" must be a list of %d numbers, got %r'
                          % (index, entry.get('child', '?'), key, length, value))
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError):
        raise FramesError('frames[%d] (%s): "%s" has a non-numeric value: %r'
                          % (index, entry.get('child', '?'), key, value))
    if not all(math.isfinite(v) for v in out):
        raise FramesError('frames[%d] (%s): "%s" must be finite, got %r'
                          % (index, entry.get('child', '?'), key, value))
    return out


def parse_frames(data, root='world'):
    """Validate a loaded YAML document and return a list of StaticFrame.

    Checks: every entry has parent/child names and a finite pose; quaternions are unit length
    (within 1e-6, then renormalised); no child has two parents; every frame is connected to
    ``root`` (a tree, no cycles).
    """
    if not isinstance(data, dict) or not isinstance(data.get('frames'), list):
        raise FramesError('expected a mapping with a "frames" list')
    frames = []
    parents = {}
    for i, entry in enumerate(data['frames']):
        if not isinstance(entry, dict):
            raise FramesError('frames[%d] is not a mapping: %r' % (i, entry))
        parent, child = entry.get('parent'), entry.get('child')
        for key, name in (('parent', parent), ('child', child)):
            if not isinstance(name, str) or not name.strip() or name.startswith('/'):
                raise FramesError('frames[%d]: "%s" must be a non-empty frame id without a '
                                  'leading slash, got %r' % (i, key, name))
        if parent == child:
            raise FramesError('frames[%d]: parent and child are both "%s"' % (i, child))
        if child in parents:
            raise FramesError('frames[%d]: "%s" already has parent "%s"' % (i, child, parents[child]))
        xyz = _vector(entry, i, 'xyz', 3)
        if 'quaternion' in entry:
            q = _vector(entry, i, 'quaternion', 4)
            n = math.sqrt(sum(v * v for v in q))
            if abs(n - 1.0) > 1e-6:
                raise FramesError('frames[%d] (%s): quaternion norm is %.9f, expected 1'
                                  % (i, child, n))
            q = [v / n for v in q]
        else:
            q = rpy_to_quaternion(*_vector(entry, i, 'rpy', 3))
        parents[child] = parent
        frames.append(StaticFrame(parent, child, xyz, q))
    for f in frames:
        seen = {f.child}
        node = f.parent
        while node != root:
            if node not in parents:
                raise FramesError('frame "%s" is not connected to "%s" (chain stops at "%s")'
                                  % (f.child, root, node))
            if node in seen:
                raise FramesError('cycle through frame "%s"' % node)
            seen.add(node)
            node = parents[node]
    return frames


def load_frames(path, root='world'):
    """Read and validate a world-frames YAML file."""
    try:
        with open(path) as stream:
            data = yaml.safe_load(stream)
    except (OSError, yaml.YAMLError) as exc:
        raise FramesError('cannot read %s: %s' % (path, exc))
    try:
        return parse_frames(data, root)
    except FramesError as exc:
        raise FramesError('%s: %s' % (path, exc))


def world_transform(frames, child, root='world'):
    """4x4 transform T_root_child composed along the static tree."""
    by_child = {f.child: f for f in frames}
    T = np.eye(4)
    node = child
    while node != root:
        f = by_child[node]
        T = f.matrix() @ T
        node = f.parent
    return T
