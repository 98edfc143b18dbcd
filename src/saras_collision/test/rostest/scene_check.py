#!/usr/bin/env python3
"""rostest node: colliding_regions on the simulated scene with one bone box.

Publishes tool-tip poses (SARAS tips in mesa_<side>/sbs_world, PSM tips in PSM<n>), leaves PSM2
without data, and checks /collision/distances, /collision/report, /collision/markers, the
virtual-fixture wrench, the health on /diagnostics and a moved bone marker against references
computed here from the known scene geometry (exact convex minimisation by ternary search,
independent of the C++ library).
"""
import math
import unittest

import numpy as np
import rospy
import tf2_ros
import rostest
from geometry_msgs.msg import PoseStamped, TransformStamped, WrenchStamped
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from saras_msgs.msg import CollisionReport
from std_msgs.msg import Float64MultiArray
from visualization_msgs.msg import MarkerArray

BONES = np.array([0.0, 0.0, 0.10])  # world -> bones_marker_frame translation
BOX_LO = BONES + np.array([-0.045, -0.0125, -0.002])
BOX_HI = BONES + np.array([-0.025, 0.0125, 0.038])
TROCAR = {"mesa_left": np.array([0.02, 0.13, 0.20]), "mesa_right": np.array([0.02, -0.13, 0.20]),
          "PSM1": np.array([0.10, -0.08, 0.22]), "PSM2": np.array([0.10, 0.08, 0.22])}
RADIUS = {"mesa_left": 0.0025, "mesa_right": 0.0025, "PSM1": 0.004, "PSM2": 0.004}
# Tool tips in world [m].
TIP = {"mesa_left": np.array([-0.015, 0.0, 0.11]), "mesa_right": np.array([0.0, -0.02, 0.08]),
       "PSM1": np.array([0.02, -0.03, 0.12])}
SBS = {"mesa_left": (np.array([0.0, 0.45, 0.0]), -math.pi / 2), "mesa_right": (np.array([0.0, -0.45, 0.0]), math.pi / 2)}
ORDER = ["mesa_left", "mesa_right", "PSM1", "PSM2"]


def rot_z(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def to_local(name, world_point):
    """Tool tip in the frame its topic uses."""
    if name in SBS:
        t, yaw = SBS[name]
        return rot_z(yaw).T @ (world_point - t)
    return world_point - TROCAR[name]


def ternary(f, lo=0.0, hi=1.0, iterations=200):
    for _ in range(iterations):
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        if f(m1) <= f(m2):
            hi = m2
        else:
            lo = m1
    return f(0.5 * (lo + hi))


def point_box(p):
    return float(np.linalg.norm(p - np.clip(p, BOX_LO, BOX_HI)))


def capsule_box(name):
    a, b = TIP[name], TROCAR[name]
    return ternary(lambda t: point_box(a + t * (b - a))) - RADIUS[name]


def capsule_capsule(n1, n2):
    a1, b1, a2, b2 = TIP[n1], TROCAR[n1], TIP[n2], TROCAR[n2]

    def inner(s):
        p = a1 + s * (b1 - a1)
        return ternary(lambda t: float(np.linalg.norm(p - a2 - t * (b2 - a2))), iterations=60)

    return ternary(inner, iterations=60) - RADIUS[n1] - RADIUS[n2]


class SceneCheck(unittest.TestCase):
    def setUp(self):
        self.distances = None
        self.report = None
        self.markers = None
        self.wrench = None
        self.inputs = []  # "colliding_regions: inputs" statuses from /diagnostics
        self.rate_status = []  # "colliding_regions: cycle rate"
        rospy.Subscriber("/collision/distances", Float64MultiArray, lambda m: setattr(self, "distances", m))
        rospy.Subscriber("/collision/report", CollisionReport, lambda m: setattr(self, "report", m))
        rospy.Subscriber("/collision/markers", MarkerArray, lambda m: setattr(self, "markers", m))
        rospy.Subscriber("/collision/mesa_left/fixture_wrench", WrenchStamped, lambda m: setattr(self, "wrench", m))
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics)
        self.pubs = {
            "mesa_left": rospy.Publisher("/mesa_left/ee_pose", PoseStamped, queue_size=1),
            "mesa_right": rospy.Publisher("/mesa_right/ee_pose", PoseStamped, queue_size=1),
            "PSM1": rospy.Publisher("/dvrk/PSM1/position_cartesian_current", PoseStamped, queue_size=1),
            "PSM2": rospy.Publisher("/dvrk/PSM2/position_cartesian_current", PoseStamped, queue_size=1),
        }
        self.frames = {"mesa_left": "mesa_left/sbs_world", "mesa_right": "mesa_right/sbs_world",
                       "PSM1": "PSM1", "PSM2": "PSM2"}

    def on_diagnostics(self, msg):
        for status in msg.status:
            if status.name.endswith("colliding_regions: inputs"):
                self.inputs.append(status)
            elif status.name.endswith("colliding_regions: cycle rate"):
                self.rate_status.append(status)

    def wait_inputs_status(self, predicate, timeout, publishing=False):
        """The first new inputs status satisfying @p predicate within @p timeout [s], else None."""
        self.inputs[:] = []
        end = rospy.Time.now() + rospy.Duration(timeout)
        while rospy.Time.now() < end and not rospy.is_shutdown():
            if publishing:
                self.spin_publishing(0.1)
            else:
                rospy.sleep(0.1)
            for status in list(self.inputs):
                if predicate(status):
                    return status
        return None

    def publish(self, name, local):
        msg = PoseStamped()
        msg.header.stamp = rospy.Time.now()
        msg.header.frame_id = self.frames[name]
        msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = local
        msg.pose.orientation.w = 1.0
        self.pubs[name].publish(msg)

    def spin_publishing(self, seconds, nan_psm2=False):
        end = rospy.Time.now() + rospy.Duration(seconds)
        rate = rospy.Rate(50)
        while rospy.Time.now() < end and not rospy.is_shutdown():
            for name in ("mesa_left", "mesa_right", "PSM1"):
                self.publish(name, to_local(name, TIP[name]))
            if nan_psm2:
                self.publish("PSM2", (float("nan"), 0.0, -0.1))
            rate.sleep()

    def test_scene(self):
        """One scenario in phases (each phase starts from the state the previous one left)."""
        self.spin_publishing(3.0)
        d = self.check_distances_fixture_markers()
        self.check_health(d)
        self.check_nan_rejected()
        self.check_moved_bones()
        self.check_inputs_stop()

    def check_distances_fixture_markers(self):
        """Distances, report, fixture wrench and markers against the references. @return the distances"""
        # Snapshot: the references below take time and the inputs go stale meanwhile.
        distances, report, wrench, markers = self.distances, self.report, self.wrench, self.markers
        self.assertIsNotNone(distances, "no /collision/distances")
        self.assertIsNotNone(report, "no /collision/report")
        d = distances.data
        self.assertEqual(len(d), 4)
        by_name = {t.tool: t for t in report.tools}
        self.assertEqual([t.tool for t in report.tools], ORDER)
        self.assertEqual(report.header.frame_id, "world")
        for i, name in enumerate(ORDER[:3]):
            bone = capsule_box(name)
            others = {o: capsule_capsule(name, o) for o in ORDER[:3] if o != name}
            nearest_tool = min(others, key=others.get)
            expected = min(bone, others[nearest_tool])
            rospy.loginfo("%s: node %.6f, reference bone %.6f, nearest tool %s %.6f", name, d[i], bone,
                          nearest_tool, others[nearest_tool])
            self.assertAlmostEqual(d[i], expected, delta=1e-6, msg=name)
            self.assertEqual(by_name[name].nearest_object, "bone_0" if bone < others[nearest_tool] else nearest_tool)
            p, q = by_name[name].point_on_tool, by_name[name].point_on_object
            gap = math.sqrt((p.x - q.x) ** 2 + (p.y - q.y) ** 2 + (p.z - q.z) ** 2)
            if d[i] > 0:
                self.assertAlmostEqual(gap, d[i], delta=1e-9)
                self.assertEqual(by_name[name].result, 1)
        # The mesa_left tip is 10 mm from the bone face x = -0.025: warning zone, 7.5 mm.
        self.assertAlmostEqual(d[0], 0.0075, delta=1e-9)
        # PSM2 has no pose: NaN and the no-data code.
        self.assertTrue(math.isnan(d[3]))
        self.assertEqual(by_name["PSM2"].result, -3)
        # Virtual fixture on mesa_left: k (warning - d) = 200 * 0.0125 = 2.5 N, clamped to 2 N,
        # along +x world = +y of mesa_left/sbs_world (yaw -90 deg).
        self.assertIsNotNone(wrench, "no fixture wrench")
        self.assertEqual(wrench.header.frame_id, "mesa_left/sbs_world")
        f = wrench.wrench.force
        self.assertAlmostEqual(f.x, 0.0, delta=1e-9)
        self.assertAlmostEqual(f.y, 2.0, delta=1e-9)
        self.assertAlmostEqual(f.z, 0.0, delta=1e-9)
        # Markers: the bone box and the closest-point lines.
        self.assertIsNotNone(markers, "no markers")
        namespaces = {m.ns for m in markers.markers}
        self.assertTrue({"bones", "tool_shafts", "tool_ends", "closest_points"} <= namespaces, namespaces)
        bone = [m for m in markers.markers if m.ns == "bones"][0]
        self.assertAlmostEqual(bone.pose.position.x, -0.035, delta=1e-9)
        self.assertAlmostEqual(bone.pose.position.z, 0.118, delta=1e-9)
        return d

    def check_health(self, d):
        """Health: PSM2 missing -> ERROR naming it once the start-up grace (tf_timeout 3 s) is over."""
        status = self.wait_inputs_status(
            lambda s: s.level == DiagnosticStatus.ERROR and "lost for: PSM2" in s.message, 6.0, publishing=True)
        self.assertIsNotNone(status, "no ERROR inputs status naming only the missing PSM2 on /diagnostics")
        self.assertEqual(status.hardware_id, "collision")
        values = {kv.key: kv.value for kv in status.values}
        self.assertEqual(values["PSM2 pose age [s]"], "no pose received")
        closest = min(range(3), key=lambda i: d[i])
        self.assertEqual(values["closest tool"], ORDER[closest])
        self.assertAlmostEqual(float(values["closest distance [m]"]), d[closest], delta=1e-6)
        self.assertTrue(self.rate_status, "no cycle rate status on /diagnostics")
        self.assertEqual(self.rate_status[-1].hardware_id, "collision")

    def check_nan_rejected(self):
        """NaN poses for PSM2 are rejected and counted; the node keeps running."""
        self.spin_publishing(1.5, nan_psm2=True)
        self.assertTrue(math.isnan(self.distances.data[3]))
        self.assertAlmostEqual(self.distances.data[0], 0.0075, delta=1e-9)
        status = self.wait_inputs_status(lambda s: True, 3.0, publishing=True)
        self.assertIsNotNone(status, "no inputs status on /diagnostics")
        self.assertGreater(int({kv.key: kv.value for kv in status.values}["poses rejected (non-finite)"]), 0)

    def check_moved_bones(self):
        """The bone marker moves: the node follows it without restart."""
        # The bone marker moves 10 mm towards the feet (new static TF): the node follows it without
        # restart; mesa_left is now 17.5 mm from the bone and the fixture force is 200 * 2.5 mm.
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = "world"
        t.child_frame_id = "bones_marker_frame"
        t.transform.translation.x, t.transform.translation.z = -0.01, 0.10
        t.transform.rotation.w = 1.0
        broadcaster = tf2_ros.StaticTransformBroadcaster()
        broadcaster.sendTransform(t)
        self.spin_publishing(1.5)
        self.assertAlmostEqual(self.distances.data[0], 0.0175, delta=1e-9)
        self.assertEqual(self.report.tools[0].nearest_object, "bone_0")
        self.assertAlmostEqual(self.wrench.wrench.force.y, 0.5, delta=1e-9)

    def check_inputs_stop(self):
        """Inputs stop: every tool stale, the fixture releases, the health says STALE."""
        # Inputs stop: after ~pose_timeout every tool is stale (NaN) and the fixture releases.
        rospy.sleep(1.0)
        self.assertTrue(all(math.isnan(x) for x in self.distances.data), self.distances.data)
        f = self.wrench.wrench.force
        self.assertEqual((f.x, f.y, f.z), (0.0, 0.0, 0.0))
        # ... and the health says so: STALE, nothing monitored.
        status = self.wait_inputs_status(lambda s: s.level == DiagnosticStatus.STALE, 3.0)
        self.assertIsNotNone(status, "inputs status not STALE with every tool pose stale")
        self.assertIn("nothing monitored", status.message)


if __name__ == "__main__":
    rospy.init_node("scene_check")
    rostest.rosrun("saras_collision", "scene_check", SceneCheck)
