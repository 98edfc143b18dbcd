"""ROS side of :class:`saras_simulation.dip_servo.DipServo` for touchball_console_sim: what the
scripted surgeon sees of each tool during a dip.

Per servo: contact_sim's tip truth (``~<side>/tip_topic``, std_msgs/Float64MultiArray [tip x, y, z
in world m, signed distance to the tissue m], 30 Hz) is handed to the servo under the console's
lock, stamped with the console's script time (a 30 Hz topic: the console's own 1 kHz loop must not
compete with 300 Hz pose streams for the interpreter). ``~<side>/dip_site`` is a point (x, y) in
``~<side>/tool_frame`` (the same for both sides: the bases are mirrored), turned into a world target
once the static transform is known (``/tf_static`` only).
"""
import math

import numpy as np
import rospy
import tf2_ros
from std_msgs.msg import Float64MultiArray
from tf2_msgs.msg import TFMessage

from saras_drivers import touchball_protocol as tp


def _rotate(q, v):
    """Rotate vector v by unit quaternion q (x, y, z, w)."""
    u = np.array(q[:3])
    return v + 2.0 * np.cross(u, np.cross(u, v) + q[3] * v)


class DipEyes(object):
    """Feeds ``servos`` (one per side, None = no servo); ``clock()`` = console time."""

    def __init__(self, cfg, sides, servos, lock, clock):
        self.world = cfg['world_frame']
        self.lock, self.clock = lock, clock
        self.buffer = tf2_ros.Buffer(rospy.Duration(10.0), debug=False)
        self.rejected = 0
        self._static = rospy.Subscriber('/tf_static', TFMessage, self._on_static, queue_size=10)
        self._subs = []
        for side, sc, servo in zip(tp.DEVICES, sides, servos):
            if servo is not None:
                state = {'servo': servo, 'site': sc['dip_site'], 'frame': sc['tool_frame'].format(side=side)}
                self._subs.append(rospy.Subscriber(sc['tip_topic'].format(side=side), Float64MultiArray,
                                                   self._on_tip, callback_args=state, queue_size=1))

    def _on_static(self, msg):
        for tr in msg.transforms:
            self.buffer.set_transform_static(tr, 'tf_static')

    def _site(self, state):
        """The dip site in world (x, y), or None while the static transform is unknown."""
        try:
            tr = self.buffer.lookup_transform(self.world, state['frame'], rospy.Time(0)).transform
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
            rospy.logwarn_throttle(10.0, 'touchball_console_sim: dip servo waits for the static transform %s -> %s'
                                   ' (%s)' % (state['frame'], self.world, e))
            return None
        q = (tr.rotation.x, tr.rotation.y, tr.rotation.z, tr.rotation.w)
        p = _rotate(q, np.array([state['site'][0], state['site'][1], 0.0]))
        return (float(p[0] + tr.translation.x), float(p[1] + tr.translation.y))

    def _on_tip(self, msg, state):
        d = msg.data
        if len(d) < 4 or not all(math.isfinite(v) for v in d[:4]):
            self.rejected += 1
            return
        servo = state['servo']
        site = self._site(state) if servo.site is None else servo.site
        with self.lock:
            servo.site = site
            servo.observe(self.clock(), tuple(d[:3]), d[3])
