"""Latest platform state as the page shows it (ROS-free, thread-safe).

:class:`FrameSlot` holds the newest JPEG of one eye (bytes as received on ``.../compressed``, never
re-encoded) and lets stream handlers wait for the next one. :class:`LiveState` holds the tool
distances, the tank energies and the component health and formats them as the JSON payload of
``/state.json`` and ``/events``. Colours follow saras_visual_feedback's overlay: red at or below
the collision threshold, yellow below the warning threshold, green otherwise, grey without data.
"""
import math
import threading

#: Tool order of /collision/distances (saras_collision).
TOOLS = ('mesa_left', 'mesa_right', 'PSM1', 'PSM2')
#: diagnostic_msgs/DiagnosticStatus levels.
LEVELS = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}


def proximity(distance, collision, warning):
    """Region of a signed distance [m]: 'collision' (<= collision), 'warning' (< warning),
    'safe', or 'unknown' (None or NaN), exactly as saras_visual_feedback's ``classify``."""
    if distance is None or (isinstance(distance, float) and math.isnan(distance)):
        return 'unknown'
    if distance <= collision:
        return 'collision'
    if distance < warning:
        return 'warning'
    return 'safe'


class FrameSlot(object):
    """Newest JPEG frame of one eye with a counter; stream handlers block on :meth:`wait_newer`."""

    def __init__(self):
        self._cond = threading.Condition()
        self._jpeg = None
        self._count = 0
        self._stamp = None
        self._closed = False

    def put(self, jpeg, stamp):
        """Store a JPEG (bytes) stamped ``stamp`` [s] and wake the waiters."""
        with self._cond:
            self._jpeg = bytes(jpeg)
            self._stamp = stamp
            self._count += 1
            self._cond.notify_all()

    def latest(self):
        """(count, jpeg or None, stamp or None)."""
        with self._cond:
            return self._count, self._jpeg, self._stamp

    def wait_newer(self, count, timeout):
        """(count, jpeg) of a frame newer than ``count``, or None after ``timeout`` [s] or on close."""
        with self._cond:
            self._cond.wait_for(lambda: self._closed or (self._count > count and self._jpeg is not None), timeout)
            if self._closed or self._count <= count or self._jpeg is None:
                return None
            return self._count, self._jpeg

    def close(self):
        """Release every waiter (server shutdown)."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()


class LiveState(object):
    """Distances, energies and health, newest values with their receive time [s]."""

    def __init__(self, thresholds, colours, energy_names, stale_after):
        """``thresholds``: {'collision': m, 'warning': m}; ``colours``: {'collision'|'warning'|'safe'|
        'unknown': '#rrggbb'}; ``energy_names``: display names of the tanks in order;
        ``stale_after`` [s]: older values are shown as stale."""
        self._lock = threading.Lock()
        self.thresholds = dict(thresholds)
        self.colours = dict(colours)
        self.stale_after = float(stale_after)
        self._distances = (None, None)            # (values, receive time)
        self._energies = {n: (None, None) for n in energy_names}
        self._energy_names = tuple(energy_names)
        self._health = (None, None)               # ([(name, level, message)], receive time)
        self.frames = {'left': FrameSlot(), 'right': FrameSlot()}

    def set_distances(self, values, now):
        with self._lock:
            self._distances = (tuple(float(v) for v in values), now)

    def set_energy(self, name, value, now):
        with self._lock:
            if name in self._energies:
                self._energies[name] = (float(value), now)

    def set_health(self, statuses, now):
        """``statuses``: iterable of (name, level, message) of the aggregator's groups."""
        with self._lock:
            self._health = ([(str(n), int(l), str(m)) for n, l, m in statuses], now)

    def _age(self, t, now):
        return None if t is None else max(0.0, now - t)

    def _fresh(self, t, now):
        return t is not None and now - t <= self.stale_after

    def snapshot(self, now):
        """JSON-ready dict of everything the page shows (see README, "Payload")."""
        with self._lock:
            dist, dist_t = self._distances
            energies = dict(self._energies)
            health, health_t = self._health
        fresh = self._fresh(dist_t, now)
        tools = []
        for i, name in enumerate(TOOLS):
            d = dist[i] if dist is not None and i < len(dist) and fresh else None
            d = None if d is not None and math.isnan(d) else d
            region = proximity(d, self.thresholds['collision'], self.thresholds['warning'])
            tools.append({'tool': name, 'distance_mm': _mm(d), 'region': region, 'colour': self.colours[region]})
        tanks = []
        for name in self._energy_names:
            value, t = energies[name]
            tanks.append({'tank': name, 'energy_j': _finite(value) if self._fresh(t, now) else None,
                          'age_s': _round(self._age(t, now))})
        groups = []
        for name, level, message in (health or []):
            stale = not self._fresh(health_t, now)
            lvl = 3 if stale else level
            groups.append({'name': name, 'level': LEVELS.get(lvl, 'ERROR'), 'message': message})
        frames = {}
        for eye, slot in self.frames.items():
            count, jpeg, stamp = slot.latest()
            frames[eye] = {'count': count, 'bytes': len(jpeg) if jpeg else 0}
        return {'tools': tools, 'distances_age_s': _round(self._age(dist_t, now)), 'tanks': tanks,
                'health': groups, 'health_age_s': _round(self._age(health_t, now)), 'frames': frames,
                'thresholds_mm': {k: 1e3 * v for k, v in self.thresholds.items()}}

    def close(self):
        for slot in self.frames.values():
            slot.close()


def _finite(v):
    return v if v is not None and math.isfinite(v) else None


def _mm(d):
    return round(1e3 * d, 1) if d is not None and math.isfinite(d) else None


def _round(v):
    return None if v is None else round(v, 2)


def aggregator_groups(statuses):
    """Top-level groups of a /diagnostics_agg array: [(name, level, message)] for each status
    whose name is '/<group>' (base_path ''), in the aggregator's order."""
    out = []
    for name, level, message in statuses:
        if name.startswith('/') and name.count('/') == 1 and len(name) > 1:
            out.append((name[1:], level, message))
    return out
