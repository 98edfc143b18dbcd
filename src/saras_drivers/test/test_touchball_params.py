"""Start-up parameter validation: defaults, int->float, clear errors naming the parameter."""
import pytest

from saras_drivers import touchball_params as prm

SPEC = {
    'timeout': (0.03, prm.positive, 's', 'watchdog timeout'),
    'port': (5005, prm.port, '', 'UDP port'),
    'home': ([0.0, 0.0, 0.1], prm.vector(3), 'm', 'home position'),
    'source': ('script', prm.one_of('script', 'csv'), '', 'motion source'),
}


def test_defaults_and_conversion():
    out = prm.read({'timeout': 1}, SPEC)
    assert out == {'timeout': 1.0, 'port': 5005, 'home': [0.0, 0.0, 0.1], 'source': 'script'}
    assert isinstance(out['timeout'], float)


@pytest.mark.parametrize('values,name', [
    ({'timeout': 0.0}, 'timeout'), ({'timeout': float('nan')}, 'timeout'), ({'timeout': 'x'}, 'timeout'),
    ({'port': 70000}, 'port'), ({'port': True}, 'port'), ({'home': [0, 0]}, 'home'),
    ({'home': [0, 0, float('inf')]}, 'home'), ({'source': 'bag'}, 'source'),
])
def test_errors_name_the_parameter(values, name):
    with pytest.raises(prm.ParamError) as e:
        prm.read(values, SPEC, '~')
    assert ('~%s' % name) in str(e.value)
