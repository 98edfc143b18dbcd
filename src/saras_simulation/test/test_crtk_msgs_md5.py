"""crtk_msgs types are wire-compatible with upstream collaborative-robotics/crtk_msgs 1.3.0: the
md5sums below were computed with genmsg from the upstream .msg/.srv text."""
import importlib

import pytest

UPSTREAM_MD5 = {
    'msg/CartesianImpedance': '59675c5b57c990d0b76f7f0c9954d4f3',
    'msg/CartesianImpedanceHalfPlaneGains': 'b8790a9e2c72de6fc930123c128d3b77',
    'msg/CartesianServo': '6a249c3960a5b413513e5f1e23a82d6d',
    'msg/CartesianState': '3913bf7ef8bcc8fa7a8eb33a46f273db',
    'msg/JointServo': '660a5227424e1ddeb4a13710d9166974',
    'msg/OperatingState': 'b1bd4021639d9d9c5fbfff78d6ff3158',
    'msg/SetpointMode': '45488f3061f396e81b1a70a7e6acdfa4',
    'msg/StringStamped': '5e3e46086181199270f1ac3a28a5977f',
    'srv/QueryForwardKinematics': '787c6da7a75e9886573c4af11f1a381f',
    'srv/QueryInverseKinematics': 'ce8dbc3b4384e2f7567488e7e75496d8',
    'srv/TriggerOperatingState': 'd941a2d049e2c9ac5773fc4a3a8a892d',
}


@pytest.mark.parametrize('name', sorted(UPSTREAM_MD5))
def test_md5_matches_upstream(name):
    kind, typ = name.split('/')
    module = importlib.import_module('crtk_msgs.' + kind)
    assert getattr(module, typ)._md5sum == UPSTREAM_MD5[name]
