"""Make the cores importable without a built devel space (pytest from the workspace root):
this package's, saras_common's transforms and saras_description's kinematics (pipeline test).
Appended: a built devel space takes precedence."""
import os
import sys

_HERE = os.path.dirname(os.path.abspath(__file__))
for _p in (os.path.join(_HERE, '..', 'src'), os.path.join(_HERE, '..', '..', 'saras_common', 'src'),
           os.path.join(_HERE, '..', '..', 'saras_description', 'src')):
    if os.path.isdir(_p) and _p not in sys.path:
        sys.path.append(_p)
