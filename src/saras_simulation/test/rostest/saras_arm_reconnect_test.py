#!/usr/bin/env python3
"""rostest (saras_arms_driver against an in-process simulator server that this test can cut and
restart): a dropped link leaves the arm holding, the driver reconnects with backoff, and no old
target is replayed -- neither after a network drop nor after a robot restart."""
import sys
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Bool

from saras_drivers import saras_arm_kinematics as sak
from saras_drivers import keys
from saras_simulation.saras_arm_model import SarasArmModel
from saras_simulation.saras_arm_server import SarasArmServer


import diag_status

FRAME = 'mesa_left/sbs_world'


def wait(pred, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


class TestReconnect(unittest.TestCase):
    def make_server(self):
        model = SarasArmModel(sak.load('left'), max_velocity=0.2)
        server = SarasArmServer(model, '127.0.0.1', rospy.get_param('~port'), 600.0, 100.0, key=keys.read_key_file(rospy.get_param('~key_file')))
        server.start_in_thread()
        return model, server

    def send(self, position):
        m = PoseStamped()
        m.header.frame_id = FRAME
        m.header.stamp = rospy.Time.now()
        m.pose.position.x, m.pose.position.y, m.pose.position.z = position
        self.pub.publish(m)

    def driver_ok(self):
        s = [m for m in self.status if m.component == 'mesa_left/saras_arms_driver']
        return bool(s) and s[-1].level == diag_status.OK

    def test_reconnect(self):
        self.status = []
        diag_status.subscribe(self.status)
        self.pub = rospy.Publisher('/mesa_left/target_pose', PoseStamped, queue_size=10)
        links = []   # /mesa_left/arm_link (latched): the teleoperation re-synchronises on false, then true
        rospy.Subscriber('/mesa_left/arm_link', Bool, lambda m: links.append(m.data))
        self.assertTrue(wait(lambda: links and not any(links), 10.0), 'arm_link false not latched before the connection')
        model, server = self.make_server()
        self.assertTrue(wait(lambda: server.sids, 20.0), 'driver did not connect')
        self.assertTrue(wait(lambda: links[-1:] == [True], 5.0), 'arm_link not true once connected: %s' % links)
        self.assertTrue(wait(lambda: server.events.get('hold', 0) >= 1, 5.0), 'no hold on connect')
        time.sleep(0.5)
        far = model.q.copy()
        far[:2] += 0.4
        goal = model.tip_in_base(far)[:3, 3]
        for _ in range(5):
            self.send(goal)
            time.sleep(0.02)
        self.assertTrue(wait(lambda: model.moving, 5.0), 'arm did not start moving')
        # --- network drop while moving: the robot holds, nothing is replayed on reconnection
        server.drop_clients()
        self.assertTrue(wait(lambda: not model.moving, 1.0), 'arm kept moving after the drop')
        held = model.q.copy()
        targets_before = server.events.get('set_target', 0)
        self.assertFalse(np.allclose(held, far))
        self.assertTrue(wait(lambda: not self.driver_ok(), 2.0), 'driver did not report the drop')
        self.assertTrue(wait(lambda: links[-1:] == [False], 2.0), 'arm_link not false after the drop: %s' % links)
        for _ in range(5):                                 # published during the outage: not queued
            self.send(goal)
            time.sleep(0.01)
        self.assertTrue(wait(lambda: server.sids and self.driver_ok(), 15.0), 'no reconnection')
        self.assertTrue(wait(lambda: links[-1:] == [True], 2.0), 'arm_link not true after the reconnection')
        time.sleep(1.0)
        self.assertEqual(server.events.get('set_target', 0), targets_before, 'old target replayed')
        self.assertFalse(model.moving)
        np.testing.assert_allclose(model.q, held, atol=0)
        self.assertGreaterEqual(server.events.get('hold', 0), 2)
        # --- robot restart: a new server on the same port, still nothing replayed
        server.stop()
        self.assertTrue(wait(lambda: not self.driver_ok(), 3.0))
        model2, server2 = self.make_server()
        q0 = model2.q.copy()
        self.assertTrue(wait(lambda: server2.sids and self.driver_ok(), 20.0), 'no reconnection')
        time.sleep(1.0)
        self.assertEqual(server2.events.get('set_target', 0), 0, 'old target replayed after restart')
        np.testing.assert_allclose(model2.q, q0, atol=0)
        # --- and fresh targets work again
        near = q0.copy()
        near[0] += 0.05
        goal2 = model2.tip_in_base(near)[:3, 3]
        self.send(goal2)
        self.assertTrue(wait(lambda: np.linalg.norm(model2.tip_in_base()[:3, 3] - goal2) < 1e-9, 10.0))
        server2.stop()


if __name__ == '__main__':
    rospy.init_node('saras_arm_reconnect_test')
    rostest.rosrun('saras_simulation', 'saras_arm_reconnect', TestReconnect, sys.argv)
