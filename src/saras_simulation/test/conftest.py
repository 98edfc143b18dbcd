"""pytest: the ROS-free tests of this directory only; test/rostest/ holds rostest nodes (run by
catkin through the .test files) and test/data/ their inputs."""
collect_ignore = ['rostest', 'data']
