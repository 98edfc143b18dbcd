"""Static frames files of the platform: THE parser and validator of the frames-YAML format.

Used by every package that reads the format (saras_bringup's world_frames node, the URDF generator
and hand-eye loader of this package, the calibration suite, the dVRK simulator), so the format has
one definition. The file format (saras_calibration writes it)::

    frames:
      - {parent: world, child: PSM1, xyz: [0.10, -0.08, 0.22], rpy: [0.0, 0.0, 0.0]}

``xyz`` in metres, ``rpy`` in radians (fixed axes: roll about x, pitch about y, yaw about z,
i.e. R = Rz(yaw) Ry(pitch) Rx(roll), the URDF / tf convention). A ``quaternion: [x, y, z, w]``
may be given instead of ``rpy``. No ROS import here.

:func:`parse_frames` checks the tree against a ``root`` frame (``world`` for world_frames.yaml);
``root=None`` accepts any forest (e.g. the hand-eye file ``ECM/tool_tip -> endoscope/...``).
"""
import math

import numpy as np
import yaml
from saras_common.transforms import matrix_to_rpy, quaternion_from_matrix, quaternion_to_matrix, rpy_to_matrix

__all__ = ['FramesError', 'StaticFrame', 'parse_frames', 'load_frames', 'world_transform', 'frames_by_child']


class FramesError(ValueError):
    """A world-frames file that cannot be used; the message names the entry and the field."""


class StaticFrame(object):
    """One static transform parent -> child.

    ``translation`` (alias ``xyz``) [m], unit ``quaternion`` (x, y, z, w) and ``rpy`` [rad] (as
    written in the file, or derived from the quaternion).
    """

    __slots__ = ('parent', 'child', 'translation', 'quaternion', 'rpy')

    def __init__(self, parent, child, translation, quaternion, rpy=None):
        self.parent = parent
        self.child = child
        self.translation = tuple(float(v) for v in translation)
        self.quaternion = tuple(float(v) for v in quaternion)
        if rpy is None:
            rpy = matrix_to_rpy(quaternion_to_matrix(self.quaternion))
        self.rpy = tuple(float(v) for v in rpy)

    @property
    def xyz(self):
        """Translation [m] (the file's key)."""
        return self.translation

    def matrix(self):
        """4x4 homogeneous transform T_parent_child."""
        T = np.eye(4)
        T[:3, :3] = quaternion_to_matrix(self.quaternion)
        T[:3, 3] = self.translation
        return T

    def __repr__(self):
        return 'StaticFrame(%s -> %s, t=%s, q=%s)' % (self.parent, self.child,
                                                       self.translation, self.quaternion)


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
    (within 1e-6, then renormalised); no child has two parents; no cycles; with a ``root``, every
    frame is connected to it.
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
        rpy = None
        if 'quaternion' in entry:
            q = _vector(entry, i, 'quaternion', 4)
            n = math.sqrt(sum(v * v for v in q))
            if abs(n - 1.0) > 1e-6:
                raise FramesError('frames[%d] (%s): quaternion norm is %.9f, expected 1'
                                  % (i, child, n))
            q = [v / n for v in q]
        else:
            rpy = _vector(entry, i, 'rpy', 3)
            q = quaternion_from_matrix(rpy_to_matrix(rpy))
        parents[child] = parent
        frames.append(StaticFrame(parent, child, xyz, q, rpy))
    for f in frames:
        seen = {f.child}
        node = f.parent
        while node != root:
            if node not in parents:
                if root is None:
                    break
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


def frames_by_child(frames):
    """``{child: (parent, T_parent_child)}`` of a frame list (4x4 numpy transforms)."""
    return {f.child: (f.parent, f.matrix()) for f in frames}


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
