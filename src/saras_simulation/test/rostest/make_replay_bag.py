#!/usr/bin/env python3
"""Write test/data/dvrk_replay.bag: 2 s of dVRK 1.x arm topics at 50 Hz, as a real dVRK records.

Independent of dvrk_sim: PSM poses are analytic (sinusoidal positions, fixed orientation), joint
values are sinusoids. ECM has joint states only (dvrk_sim must compute its cartesian pose), and
PSM2 carries one NaN pose at sample 40 (dvrk_sim must drop it and go on).
Usage: make_replay_bag.py [output.bag]
"""
import math
import os
import sys

import rosbag
import rospy
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState

PSM = ['outer_yaw', 'outer_pitch', 'outer_insertion', 'outer_roll', 'outer_wrist_pitch', 'outer_wrist_yaw']
ECM = ['outer_yaw', 'outer_pitch', 'insertion', 'outer_roll']


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..', 'data',
                                                             'dvrk_replay.bag')
    t0 = 1600000000.0
    with rosbag.Bag(out, 'w', compression=rosbag.Compression.BZ2) as bag:
        for i in range(100):
            t = i * 0.02
            stamp = rospy.Time.from_sec(t0 + t)
            for k, arm in enumerate(('PSM1', 'PSM2')):
                cp = PoseStamped()
                cp.header.stamp, cp.header.frame_id = stamp, arm
                cp.pose.position.x = -0.07 + 0.01 * math.sin(2 * math.pi * 0.5 * t + k)
                cp.pose.position.y = 0.04 * (1 - 2 * k) + 0.01 * math.cos(2 * math.pi * 0.5 * t)
                cp.pose.position.z = -0.13 + 0.005 * math.sin(2 * math.pi * t)
                cp.pose.orientation.x, cp.pose.orientation.w = 1.0, 0.0
                if arm == 'PSM2' and i == 40:
                    cp.pose.position.x = float('nan')
                bag.write('/dvrk/%s/position_cartesian_current' % arm, cp, stamp)
                js = JointState()
                js.header.stamp, js.name = stamp, PSM
                js.position = [0.3 * math.sin(t + j + k) for j in range(6)]
                js.position[2] = 0.14 + 0.01 * math.sin(t)
                bag.write('/dvrk/%s/state_joint_current' % arm, js, stamp)
            js = JointState()
            js.header.stamp, js.name = stamp, ECM
            js.position = [-0.6 + 0.05 * t, 0.0, 0.09, 0.01 * t]
            bag.write('/dvrk/ECM/state_joint_current', js, stamp)


if __name__ == '__main__':
    main()
