# ROS-free core modules of saras_simulation (installed by catkin_python_setup).
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['saras_simulation'], package_dir={'': 'src'}))
