"""saras_description: URDF generator and numpy kinematics of the MULTIROBOTS-SURGERY platform.

ROS-agnostic core (numpy + PyYAML only; rotations and 4x4 transforms come from
:mod:`saras_common.transforms`):

* :mod:`saras_description.geometry`   -- dimensions and joint limits of every robot, as data.
* :mod:`saras_description.config`     -- loading and validation of the package's YAML files.
* :mod:`saras_description.kinematics` -- forward/inverse kinematics that match the URDFs.
* :mod:`saras_description.urdf`       -- URDF generators (``scripts/make_urdf`` is the CLI).
"""
