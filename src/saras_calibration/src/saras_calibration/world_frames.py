"""Static world-frame YAML of the platform (``saras_bringup/config/world_frames.yaml`` format).

Format::

    frames:
      - {parent: world, child: PSM1, xyz: [0.10, -0.08, 0.22], rpy: [0.0, 0.0, 0.0]}

``xyz`` in metres, ``rpy`` in radians (fixed axes: roll about x, then pitch about y, then yaw
about z). :func:`registration_frames` turns per-arm registrations into these entries.
"""
import datetime
import os

import numpy as np
from saras_description.frames import FramesError, load_frames, parse_frames

from saras_common.transforms import inverse, rpy_from_transform, transform_from_rpy, validate_transform

__all__ = ['WorldFramesError', 'load_world_frames', 'save_world_frames', 'frame_entry',
           'registration_frames', 'merge_frames', 'entry_transform']


class WorldFramesError(ValueError):
    """Malformed world-frame file or entry."""


def frame_entry(parent, child, T):
    """One YAML entry for ``T_parent_child`` (rounded to 0.1 um / 1 nrad)."""
    T = validate_transform(T, '%s->%s' % (parent, child))
    xyz, rpy = rpy_from_transform(T)
    return {'parent': str(parent), 'child': str(child),
            'xyz': [round(float(v), 7) for v in xyz], 'rpy': [round(float(v), 9) for v in rpy]}


def entry_transform(entry):
    """4x4 ``T_parent_child`` of an entry."""
    return transform_from_rpy(entry['xyz'], entry['rpy'])


def _entry(frame):
    return {'parent': frame.parent, 'child': frame.child, 'xyz': list(frame.xyz), 'rpy': list(frame.rpy)}


def _validated(entries, where):
    """Entries checked by the platform's one parser of the format (saras_description.frames)."""
    try:
        return [_entry(f) for f in parse_frames({'frames': list(entries)}, root=None)]
    except FramesError as exc:
        raise WorldFramesError('%s: %s' % (where, exc))


def load_world_frames(path):
    """List of entries ``{parent, child, xyz, rpy}`` of a world-frame YAML file (quaternion entries
    are converted to rpy). Raises :class:`WorldFramesError`."""
    try:
        return [_entry(f) for f in load_frames(path, root=None)]
    except FramesError as exc:
        raise WorldFramesError(str(exc))


def save_world_frames(path, entries, comment=None):
    """Write entries in the platform format (one flow-style line per frame)."""
    lines = ['# Static transforms written by saras_calibration on %s UTC.'
             % datetime.datetime.utcnow().strftime('%Y-%m-%d %H:%M:%S'),
             '# Format: parent, child, xyz [m], rpy [rad] (fixed axes: roll about x, then pitch about y, then yaw about z).']
    if comment:
        lines += ['# ' + c for c in comment.splitlines()]
    lines.append('frames:')
    for e in _validated(entries, path):
        lines.append('  - {parent: %s, child: %s, xyz: [%s], rpy: [%s]}' % (
            e['parent'], e['child'], ', '.join(repr(float(v)) for v in e['xyz']),
            ', '.join(repr(float(v)) for v in e['rpy'])))
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    tmp = path + '.tmp'
    with open(tmp, 'w') as f:
        f.write('\n'.join(lines) + '\n')
    os.replace(tmp, path)


def registration_frames(bases_to_pattern, world_frame='world', T_world_pattern=None):
    """World-frame entries from per-robot registrations.

    :param bases_to_pattern: dict base frame name -> 4x4 ``T_base_pattern`` (pattern in the
        robot base, from touched dots or from the endoscope chain).
    :param T_world_pattern: pose of the pattern in the world [m]; default identity (the world
        frame *is* the pattern frame).
    :returns: list of entries ``world -> base`` with ``T_world_base = T_world_pattern @ inv(T_base_pattern)``.
    """
    Twp = np.eye(4) if T_world_pattern is None else validate_transform(T_world_pattern, 'T_world_pattern')
    return [frame_entry(world_frame, base, Twp @ inverse(validate_transform(T, base)))
            for base, T in bases_to_pattern.items()]


def merge_frames(template, updates):
    """Replace template entries with the same child by ``updates``; append new ones."""
    upd = {e['child']: e for e in updates}
    out = [upd.pop(e['child'], e) for e in template]
    return out + [e for e in updates if e['child'] in upd]
