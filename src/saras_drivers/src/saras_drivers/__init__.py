"""SARAS platform drivers and simulators: ROS-agnostic cores (no rospy import here)."""
