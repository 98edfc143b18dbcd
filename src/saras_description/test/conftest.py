"""Make the package's core importable without a built devel space (tests need no roscore)."""
import os
import sys

_HERE = os.path.dirname(os.path.abspath(__file__))
for _p in (os.path.join(_HERE, '..', 'src'), os.path.join(_HERE, '..', '..', 'saras_common', 'src')):
    _p = os.path.abspath(_p)
    if _p not in sys.path:
        sys.path.insert(0, _p)
