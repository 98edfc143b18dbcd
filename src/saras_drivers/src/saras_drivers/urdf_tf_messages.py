"""tf2_msgs/TFMessage adapter of :class:`saras_drivers.saras_arm_tf.UrdfTf` (what
robot_state_publisher broadcasts), shared by the nodes that broadcast a robot's TF themselves
(``saras_arms_state`` and ``dvrk_sim`` with their TF options).

The moving-joint message is allocated once, in the order of ``UrdfTf.movable``, and refilled in
place per joint sample (no per-sample message allocation). Units: m, quaternion [x, y, z, w], s.

:class:`RateLimiter` throttles the moving-joint broadcast like robot_state_publisher's
``publish_frequency`` (default 50 Hz there): the joint states keep their full rate, /tf carries the
samples on a ``1 / rate`` grid.
"""
from saras_common.transforms import set_transform_msg, transform_stamped
from tf2_msgs.msg import TFMessage


class RateLimiter(object):
    """Which samples to broadcast so that /tf carries ``rate`` [Hz] on average (``rate`` 0: every
    sample). A sample at time ``t`` [s] is due when ``t`` reaches the next grid instant; the grid
    advances by ``1 / rate`` (no drift when samples jitter) and restarts at ``t`` after a gap or a
    clock jump (more than one period behind, or time going backwards)."""

    def __init__(self, rate):
        if isinstance(rate, bool) or not isinstance(rate, (int, float)) or \
                not 0.0 <= rate < float('inf'):
            raise ValueError('TF rate must be a finite number >= 0 Hz, got %r' % rate)
        self.period = 1.0 / float(rate) if rate > 0.0 else 0.0
        self.next = None    # next grid instant [s]
        self.last = None    # time of the last due sample [s]

    def due(self, t):
        """True if the sample at ``t`` [s] is to be broadcast (and then counts as broadcast)."""
        t = float(t)
        if self.period == 0.0:
            return True
        if self.next is None or t < self.last or t >= self.next + self.period:
            self.next = t                 # first sample, clock jump or gap: restart the grid
        if t + 1e-9 < self.next:
            return False
        self.next += self.period
        self.last = t
        return True


class UrdfTfMessages(object):
    """TF messages of one robot: :meth:`static` (fixed joints) and :meth:`moving` (movable joints,
    one preallocated TFMessage refilled per sample)."""

    def __init__(self, urdf_tf, q0, stamp):
        """:param q0: any valid joint vector (in the order of the UrdfTf's joint_names) used to
        allocate the moving-joint message."""
        self.urdf_tf = urdf_tf
        self.msg = TFMessage()
        for parent, child, xyz, quat in urdf_tf.moving(q0):
            self.msg.transforms.append(transform_stamped(parent, child, stamp=stamp, xyz=xyz, q=quat))

    def static(self, stamp):
        """Fixed joints, for /tf_static (latched, published once)."""
        return [transform_stamped(p, c, stamp=stamp, xyz=xyz, q=quat) for p, c, xyz, quat in self.urdf_tf.fixed()]

    def moving(self, q, stamp):
        """The preallocated TFMessage refilled for joint vector ``q``, every transform stamped ``stamp``."""
        for t, (_, _, xyz, quat) in zip(self.msg.transforms, self.urdf_tf.moving(q)):
            t.header.stamp = stamp
            set_transform_msg(t.transform, xyz, quat)
        return self.msg
