"""SARAS platform hardware drivers and the protocol code they share with saras_simulation: ROS-free cores (no rospy import here)."""
