"""saras_common.diagnostics: the updater's period is put on the parameter server once."""
import pytest

from saras_common import diagnostics


class FakeParams(object):
    def __init__(self, values=None):
        self.values = dict(values or {})
        self.sets = []

    def has_param(self, name):
        return name in self.values

    def get_param(self, name):
        return self.values[name]

    def set_param(self, name, value):
        self.sets.append((name, value))
        self.values[name] = value


def test_unset_period_is_set_to_the_default_so_later_reads_are_cached():
    p = FakeParams()
    assert diagnostics.ensure_period(p) == 1.0
    assert p.sets == [('~diagnostic_period', 1.0)]
    assert diagnostics.ensure_period(p) == 1.0 and len(p.sets) == 1


def test_a_configured_period_wins():
    p = FakeParams({'~diagnostic_period': 0.5})
    assert diagnostics.ensure_period(p, 2.0) == 0.5
    assert p.sets == []


@pytest.mark.parametrize('bad', [0.0, -1.0, float('nan'), float('inf')])
def test_a_bad_default_is_refused(bad):
    with pytest.raises(ValueError):
        diagnostics.ensure_period(FakeParams(), bad)
