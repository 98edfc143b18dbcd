import saras_common


def test_package_imports():
    assert saras_common.__doc__
