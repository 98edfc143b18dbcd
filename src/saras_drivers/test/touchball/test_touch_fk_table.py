"""The stored Touch kinematics table (data/touch_fk_table.csv, read by the C++ gtest of the
receiver's inverse kinematics) equals what saras_description's forward kinematics gives today."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import touch_fk_table  # noqa: E402  pylint: disable=wrong-import-position

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'data', 'touch_fk_table.csv')


def test_stored_table_matches_reference_forward_kinematics():
    with open(DATA) as f:
        assert f.readline().strip() == touch_fk_table.HEADER
    stored = np.loadtxt(DATA, delimiter=',', skiprows=1)
    fresh = touch_fk_table.rows()
    assert stored.shape == fresh.shape == (touch_fk_table.ROWS, 13)
    np.testing.assert_allclose(stored, fresh, rtol=0.0, atol=1e-12,
                               err_msg='regenerate: python3 touch_fk_table.py > data/touch_fk_table.csv, '
                                       'then make touchIk (C++) pass test_touchball_kinematics')


def test_table_covers_the_joint_ranges():
    q = touch_fk_table.rows()[:, :6]
    limits = list(touch_fk_table.k.touch_joint_limits().values())
    for i, lim in enumerate(limits):
        span = lim.upper - lim.lower
        assert q[:, i].min() < lim.lower + 0.3 * span
        assert q[:, i].max() > lim.upper - 0.3 * span
