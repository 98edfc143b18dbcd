# ROS-free core of saras_operator_view (installed by catkin_python_setup).
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['saras_operator_view'], package_dir={'': 'src'}))
