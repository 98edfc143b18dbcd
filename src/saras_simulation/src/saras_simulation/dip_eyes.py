"""ROS side of :class:`saras_simulation.dip_servo.DipServo` for touchball_console_sim: what the
scripted surgeon sees of each tool during a dip.

Per servo: the tool tip pose (``~<side>/tool_pose_topic``, PoseStamped, at most 30 Hz used) is
brought into ``~world_frame`` through the static TF (``/tf_static`` only: the SARAS bases are
fixed, and the dynamic /tf stream is not worth its CPU here), its signed distance to the tissue
model (``~scene_file``, the scene of contact_sim and endoscope_sim) is computed and handed to the
servo under the console's lock, stamped with the console's script time. ``~<side>/dip_site`` is a
point (x, y) in the tool pose frame (the same for both sides: the bases are mirrored), turned into
a world target once the transform is known.
"""
import os
import time

import numpy as np
import rospkg
import rospy
import tf2_ros
import yaml
from geometry_msgs.msg import PoseStamped
from tf2_msgs.msg import TFMessage

from saras_drivers import touchball_protocol as tp
from saras_simulation.tissue_surface import TissueSurface


def _rotate(q, v):
    """Rotate vector v by unit quaternion q (x, y, z, w)."""
    u = np.array(q[:3])
    return v + 2.0 * np.cross(u, np.cross(u, v) + q[3] * v)


def load_surface(path):
    """Tissue surface of a scene YAML (key ``tissue``); ValueError/IOError name the file."""
    path = path or os.path.join(rospkg.RosPack().get_path('saras_simulation'), 'config', 'scene.yaml')
    with open(path) as f:
        doc = yaml.safe_load(f) or {}
    try:
        return TissueSurface.from_config(doc.get('tissue'))
    except ValueError as e:
        raise ValueError('%s: %s' % (path, e))


class DipEyes(object):
    """Feeds ``servos`` (one per side, None = no servo) from the tool poses; ``clock()`` = console time."""

    PERIOD = 1.0 / 30.0     # [s] observations used per tool

    def __init__(self, cfg, sides, servos, lock, clock):
        self.surface = load_surface(cfg['scene_file'])
        self.world = cfg['world_frame']
        self.lock, self.clock = lock, clock
        self.buffer = tf2_ros.Buffer(rospy.Duration(10.0), debug=False)
        self.failures = 0
        self._static = rospy.Subscriber('/tf_static', TFMessage, self._on_static, queue_size=10)
        self._subs = []
        for side, sc, servo in zip(tp.DEVICES, sides, servos):
            if servo is not None:
                state = {'servo': servo, 'site': sc['dip_site'], 'last': 0.0}
                self._subs.append(rospy.Subscriber(sc['tool_pose_topic'].format(side=side), PoseStamped,
                                                   self._on_pose, callback_args=state, queue_size=1))

    def _on_static(self, msg):
        for tr in msg.transforms:
            self.buffer.set_transform_static(tr, 'tf_static')

    def _on_pose(self, msg, state):
        now = time.monotonic()
        if now - state['last'] < self.PERIOD:
            return
        state['last'] = now
        try:
            tr = self.buffer.lookup_transform(self.world, msg.header.frame_id, rospy.Time(0)).transform
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            self.failures += 1
            rospy.logwarn_throttle(10.0, 'touchball_console_sim: dip servo waits for the static transform %s -> %s'
                                   ' (%s)' % (msg.header.frame_id, self.world, e))
            return
        q = (tr.rotation.x, tr.rotation.y, tr.rotation.z, tr.rotation.w)
        t = np.array([tr.translation.x, tr.translation.y, tr.translation.z])
        p = msg.pose.position
        tip = _rotate(q, np.array([p.x, p.y, p.z])) + t
        if not np.all(np.isfinite(tip)):
            return
        _, _, sd = self.surface.closest_point(tip)
        servo = state['servo']
        with self.lock:
            if servo.site is None:
                site = _rotate(q, np.array([state['site'][0], state['site'][1], 0.0])) + t
                servo.site = (float(site[0]), float(site[1]))
            servo.observe(self.clock(), tuple(tip), float(sd))
