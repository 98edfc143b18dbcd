#!/usr/bin/env python3
"""Touch kinematics table that pins the receiver's C++ inverse kinematics (touchIk in
touchball_kinematics.cpp) to the platform's reference model, saras_description's forward
kinematics (kinematics.touch_handle_in_base, which also generates the Touch URDF).

Each row: joint values q (waist, shoulder, elbow, yaw, pitch, roll) [rad] drawn inside the joint
limits, and the handle pose they give in touch_<side>/base (position [m], quaternion x, y, z, w).
The gtest (test_touchball_kinematics.cpp) requires touchIk(pose) == q for every row;
test_touch_fk_table.py regenerates the table and requires it to equal the stored file, so a
change on either side fails a test until both agree.

Regenerate: python3 touch_fk_table.py > data/touch_fk_table.csv
"""
import sys

import numpy as np

from saras_description import kinematics as k

ROWS = 64
SEED = 20
#: fraction of each joint range used (the IK's branch choice is exact only inside the limits)
MARGIN = 0.95
HEADER = 'q_waist,q_shoulder,q_elbow,q_yaw,q_pitch,q_roll,x,y,z,qx,qy,qz,qw'


def rows():
    """The table as a (ROWS, 13) array."""
    limits = list(k.touch_joint_limits().values())
    rng = np.random.default_rng(SEED)
    out = []
    for _ in range(ROWS):
        q = np.array([rng.uniform(MARGIN * lim.lower, MARGIN * lim.upper) for lim in limits])
        position, quaternion = k.pose_to_position_quaternion(k.touch_handle_in_base(q))
        if quaternion[3] < 0.0:
            quaternion = -quaternion
        out.append(np.concatenate([q, position, quaternion]))
    return np.array(out)


def write(stream):
    stream.write(HEADER + '\n')
    for r in rows():
        stream.write(','.join('%.17g' % v for v in r) + '\n')


if __name__ == '__main__':
    write(sys.stdout)
