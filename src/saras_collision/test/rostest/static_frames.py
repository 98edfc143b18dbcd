#!/usr/bin/env python3
"""Test fixture: publish static TF frames given as ~frames, a list of "parent child x y z yaw"
strings (metres, radians), on /tf_static (Debian's ROS has no static_transform_publisher)."""
import math

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped


def main():
    rospy.init_node("static_frames")
    msgs = []
    for entry in rospy.get_param("~frames"):
        parent, child, x, y, z, yaw = entry.split()
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = parent
        t.child_frame_id = child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = float(x), float(y), float(z)
        t.transform.rotation.z = math.sin(float(yaw) / 2)
        t.transform.rotation.w = math.cos(float(yaw) / 2)
        msgs.append(t)
    broadcaster = tf2_ros.StaticTransformBroadcaster()
    broadcaster.sendTransform(msgs)
    rospy.spin()


if __name__ == "__main__":
    main()
