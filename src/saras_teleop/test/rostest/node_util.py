"""Helpers of this package's rostest scripts: a node's process id, waiting for a condition."""
import time
import xmlrpc.client

import rosgraph
import rospy


def node_pid(node):
    """Process id of a running ROS node, asked through its own XML-RPC API."""
    caller = rospy.get_name()
    api = rosgraph.Master(caller).lookupNode(node)
    return xmlrpc.client.ServerProxy(api).getPid(caller)[2]


def wait_until(cond, timeout, period=0.02):
    """True as soon as cond() holds, False (cond() once more) after timeout [s]."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and not rospy.is_shutdown():
        if cond():
            return True
        time.sleep(period)
    return cond()
