# ROS-agnostic core of saras_bringup (installed by catkin_python_setup).
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['saras_bringup', 'saras_bringup.netem'],
                                 package_dir={'': 'src'}))
