"""rospy adapter of one simulated dVRK arm (dvrk_sim): dVRK 1.x topics and the dVRK 2.x CRTK
interface over a :class:`saras_simulation.crtk_arm.CrtkArm` core.

dVRK 1.x, under the dVRK namespace (``/dvrk/<ARM>/``): position_cartesian_current / _desired
(PoseStamped), state_joint_current / _desired (JointState), state_jaw_current (PSM),
state_gripper_current (MTM).

dVRK 2.x (CRTK), under ``<crtk_ns>/<ARM>/`` (root by default, as the dVRK 2.x console), the topics
crtk_python_client / dvrk_python connect to:
  published   operating_state (crtk_msgs/OperatingState, latched, on every change), measured_js,
              measured_cp, measured_cv, setpoint_js, setpoint_cp, local/measured_cp,
              local/setpoint_cp, {spatial,body}/jacobian (Float64MultiArray), {spatial,body}/measured_cf
              (zero: no force sensing), trajectory_j/ratio, jaw/measured_js + jaw/setpoint_js (PSM),
              gripper/measured_js (MTM)
  subscribed  state_command (crtk_msgs/StringStamped), servo_jp, servo_jr, servo_cp, move_jp,
              move_jr, move_cp, hold, jaw/servo_jp, jaw/move_jp (PSM); accepted without effect (no
              effort control in simulation): free, servo_jf, {spatial,body}/servo_cf,
              body/set_cf_orientation_absolute, use_gravity_compensation, trajectory_j/set_ratio,
              jaw/servo_jf, emulate_tool_present (PSM), lock_orientation, unlock_orientation,
              servo_ci (MTM)
  services    forward_kinematics, inverse_kinematics (crtk_msgs/Query*Kinematics)
Every callback only hands the command to the core under the node's lock.
"""
import numpy as np
import rospy
from crtk_msgs.msg import CartesianImpedance, OperatingState, StringStamped
from crtk_msgs.srv import (QueryForwardKinematics, QueryForwardKinematicsResponse,
                           QueryInverseKinematics, QueryInverseKinematicsResponse)
from geometry_msgs.msg import PoseStamped, Quaternion, TwistStamped, WrenchStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Empty, Float64, Float64MultiArray, MultiArrayDimension

from saras_common import transforms

from saras_simulation import dvrk_kinematics


def pose_to_matrix(pose):
    p, o = pose.position, pose.orientation
    return transforms.transform_from_quaternion((p.x, p.y, p.z), (o.x, o.y, o.z, o.w))


def fill_pose(pose, T):
    p, q = T[:3, 3], transforms.quaternion_from_matrix(T[:3, :3])
    pose.position.x, pose.position.y, pose.position.z = p
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = q


def _listened(pubs):
    """Whether any of the publishers ``pubs`` has a subscriber (else a message built for them
    would be dropped by rospy anyway)."""
    return any(p.get_num_connections() for p in pubs)


class ArmRos(object):
    """Topics of one arm. ``kind`` is 'PSM', 'ECM' or 'MTM'; ``lock`` guards ``core``."""

    def __init__(self, core, kind, joint_names, dvrk_ns, crtk_ns, lock, clock, queue_size=None):
        """``clock()``: the core's time [s] (dvrk_sim: since its start)."""
        self.core, self.kind, self.lock, self._now = core, kind, lock, clock
        self.names = list(joint_names)
        self.last_stamp = rospy.Time(0)
        self.prev_cp = None
        name = core.name
        one = '%s/%s/' % (dvrk_ns.rstrip('/'), name)
        pub = lambda n, t, **kw: rospy.Publisher(n, t, queue_size=queue_size, tcp_nodelay=True, **kw)
        self.v1 = {'cp': pub(one + 'position_cartesian_current', PoseStamped),
                   'js': pub(one + 'state_joint_current', JointState),
                   'sp_cp': pub(one + 'position_cartesian_desired', PoseStamped),
                   'sp_js': pub(one + 'state_joint_desired', JointState)}
        if kind == 'PSM':
            self.v1['jaw'] = pub(one + 'state_jaw_current', JointState)
        elif kind == 'MTM':
            self.v1['jaw'] = pub(one + 'state_gripper_current', JointState)
        self.msgs = {'cp': PoseStamped(), 'js': JointState(name=self.names),
                     'jaw': JointState(name=['jaw' if kind == 'PSM' else 'gripper']), 'cv': TwistStamped()}
        self.msgs['cp'].header.frame_id = self.msgs['cv'].header.frame_id = name
        self.v2 = {}
        self.subs = []
        self.services = []
        if crtk_ns is not None:
            self._crtk(('%s/%s/' % (crtk_ns.rstrip('/'), name)), pub)

    # ------------------------------------------------------------------ CRTK wiring
    def _crtk(self, ns, pub):
        self.v2 = {'cp': [pub(ns + 'measured_cp', PoseStamped), pub(ns + 'local/measured_cp', PoseStamped)],
                   'sp_cp': [pub(ns + 'setpoint_cp', PoseStamped), pub(ns + 'local/setpoint_cp', PoseStamped)],
                   'js': [pub(ns + 'measured_js', JointState)], 'sp_js': [pub(ns + 'setpoint_js', JointState)],
                   'cv': [pub(ns + 'measured_cv', TwistStamped)],
                   'jacobian': [pub(ns + 'spatial/jacobian', Float64MultiArray),
                                pub(ns + 'body/jacobian', Float64MultiArray)],
                   'cf': [pub(ns + 'spatial/measured_cf', WrenchStamped),
                          pub(ns + 'body/measured_cf', WrenchStamped)]}
        self.state_pub = rospy.Publisher(ns + 'operating_state', OperatingState, queue_size=50, latch=True)
        ratio = rospy.Publisher(ns + 'trajectory_j/ratio', Float64, queue_size=1, latch=True)
        ratio.publish(Float64(1.0))
        self.v2['ratio'] = [ratio]
        sub = lambda n, t, cb: self.subs.append(rospy.Subscriber(ns + n, t, cb, queue_size=10))
        sub('state_command', StringStamped, self._on_state_command)
        sub('servo_jp', JointState, lambda m: self._joint_cmd('servo_jp', m))
        sub('move_jp', JointState, lambda m: self._joint_cmd('move_jp', m))
        sub('servo_jr', JointState, lambda m: self._joint_cmd('servo_jp', m, relative=True))
        sub('move_jr', JointState, lambda m: self._joint_cmd('move_jp', m, relative=True))
        sub('servo_cp', PoseStamped, lambda m: self._cart_cmd('servo_cp', m))
        sub('move_cp', PoseStamped, lambda m: self._cart_cmd('move_cp', m))
        sub('hold', Empty, self._on_hold)
        ignored = [('free', Empty), ('servo_jf', JointState), ('spatial/servo_cf', WrenchStamped),
                   ('body/servo_cf', WrenchStamped), ('body/set_cf_orientation_absolute', Bool),
                   ('use_gravity_compensation', Bool), ('trajectory_j/set_ratio', Float64)]
        if self.kind == 'PSM':
            self.v2['jaw'] = [pub(ns + 'jaw/measured_js', JointState)]
            self.v2['sp_jaw'] = [pub(ns + 'jaw/setpoint_js', JointState)]
            sub('jaw/servo_jp', JointState, lambda m: self._joint_cmd('servo_jp', m, group='jaw'))
            sub('jaw/move_jp', JointState, lambda m: self._joint_cmd('move_jp', m, group='jaw'))
            ignored += [('jaw/servo_jf', JointState), ('emulate_tool_present', Bool)]
        elif self.kind == 'MTM':
            self.v2['jaw'] = [pub(ns + 'gripper/measured_js', JointState)]
            ignored += [('lock_orientation', Quaternion), ('unlock_orientation', Empty),
                        ('servo_ci', CartesianImpedance)]
        for n, t in ignored:
            sub(n, t, lambda m: None)
        self.services = [rospy.Service(ns + 'forward_kinematics', QueryForwardKinematics, self._fk),
                         rospy.Service(ns + 'inverse_kinematics', QueryInverseKinematics, self._ik)]

    # ------------------------------------------------------------------ commands
    def _warn(self, ok):
        if not ok:
            rospy.logwarn_throttle(1.0, 'dvrk_sim %s: command rejected: %s'
                                   % (self.core.name, self.core.last_reason))

    def _on_state_command(self, msg):
        with self.lock:
            try:
                self.core.state_command(msg.string, self._now())
            except ValueError as ex:
                self.core.rejected += 1
                rospy.logwarn('dvrk_sim %s: %s', self.core.name, ex)

    def _joint_cmd(self, what, msg, group='joints', relative=False):
        with self.lock:
            g = getattr(self.core, group)
            q = np.asarray(msg.position, dtype=float)
            if relative and q.shape == g.q.shape:
                q = g.q + q
            try:
                ok = getattr(self.core, what)(q, self._now(), group=group)
            except ValueError as ex:
                self.core.rejected += 1
                self.core.last_reason = str(ex)
                ok = False
            self._warn(ok)

    def _cart_cmd(self, what, msg):
        T = pose_to_matrix(msg.pose)
        with self.lock:
            self._warn(getattr(self.core, what)(T, self._now()))

    def _on_hold(self, _msg):
        with self.lock:
            self.core.joints.move = None
            self.core.events.append(self.core.snapshot())

    def _fk(self, req):
        res = QueryForwardKinematicsResponse()
        try:
            fill_pose(res.cp, self.core.chain.fk(np.asarray(req.jp, dtype=float)))
            res.result = True
        except ValueError as ex:
            res.result, res.message = False, str(ex)
        return res

    def _ik(self, req):
        res = QueryInverseKinematicsResponse()
        ref = np.asarray(req.jp, dtype=float) if len(req.jp) == self.core.chain.n else self.core.joints.q
        q, residual = self.core.chain.ik(pose_to_matrix(req.cp), ref)
        res.jp, res.result = list(q), residual <= self.core.ik_tolerance
        res.message = '' if res.result else 'residual %.3g' % residual
        return res

    # ------------------------------------------------------------------ publication (tick)
    def publish_state_events(self, events):
        """Operating-state events, each with a stamp after the previous one."""
        for state, homed, busy in events:
            stamp = max(rospy.Time.now(), self.last_stamp + rospy.Duration(0, 1000))
            self.last_stamp = stamp
            m = OperatingState(state=state, is_homed=homed, is_busy=busy)
            m.header.stamp = stamp
            if self.v2:
                self.state_pub.publish(m)

    def publish(self, q, jaw, stamp, with_aux=False, T=None):
        """Measured = set-point (perfect tracking). ``T``: the tip pose of ``q`` when the caller has
        it (else computed here). ``with_aux``: also jacobians and wrenches. The messages are
        allocated once and refilled: rospy serialises them in publish()."""
        J = None
        if with_aux and self.v2 and _listened(self.v2['jacobian']):
            T, J = self.core.chain.fk(q, jacobian=True)
        elif T is None:
            T = self.core.chain.fk(q)
        cp, js = self.msgs['cp'], self.msgs['js']
        cp.header.stamp = stamp
        fill_pose(cp.pose, T)
        js.header.stamp = stamp
        js.position = q.tolist() if hasattr(q, 'tolist') else list(q)
        self._send(('cp', 'sp_cp'), cp)
        self._send(('js', 'sp_js'), js)
        if jaw is not None and 'jaw' in self.v1:
            jm = self.msgs['jaw']
            jm.header.stamp = stamp
            jm.position = jaw.tolist() if hasattr(jaw, 'tolist') else list(jaw)
            self._send(('jaw', 'sp_jaw'), jm)
        if self.v2:
            cv = self.msgs['cv']
            cv.header.stamp = stamp
            v = (0.0,) * 6
            if self.prev_cp is not None and stamp > self.prev_cp[0] and _listened(self.v2['cv']):
                v = dvrk_kinematics.twist(self.prev_cp[1], T, (stamp - self.prev_cp[0]).to_sec())
            (cv.twist.linear.x, cv.twist.linear.y, cv.twist.linear.z,
             cv.twist.angular.x, cv.twist.angular.y, cv.twist.angular.z) = v
            self.prev_cp = (stamp, T)
            for p in self.v2['cv']:
                p.publish(cv)
            if with_aux:
                self._publish_aux(J, T, stamp)
        return T

    def _send(self, keys, msg):
        for k in keys:
            if k in self.v1:
                self.v1[k].publish(msg)
            for p in self.v2.get(k, ()):
                p.publish(msg)

    def _publish_aux(self, J, T, stamp):
        """Jacobians (``J`` None: nobody listens to them) and the (zero) wrenches."""
        if J is not None:
            body = np.zeros_like(J)
            Rt = T[:3, :3].T
            body[:3], body[3:] = Rt @ J[:3], Rt @ J[3:]
            for p, M in zip(self.v2['jacobian'], (J, body)):
                m = Float64MultiArray(data=list(M.ravel()))
                m.layout.dim = [MultiArrayDimension('rows', M.shape[0], M.size),
                                MultiArrayDimension('cols', M.shape[1], M.shape[1])]
                p.publish(m)
        w = WrenchStamped()
        w.header.stamp, w.header.frame_id = stamp, self.core.name
        for p in self.v2['cf']:
            p.publish(w)
