"""saras_common.params: the ROS-free core (read, rules, error text)."""
import math

import pytest

from saras_common import params as prm

SPEC = {
    'rate': (30.0, prm.in_range(0.0, 1000.0, low_open=True), 'Hz', 'publication rate'),
    'host': ('127.0.0.1', prm.non_empty_text, '', 'robot address'),
    'port': (5001, prm.port, '', 'robot TCP port'),
    'timeout': (0.1, prm.positive, 's', 'no state for this long => STALE'),
    'side': ('left', prm.one_of('left', 'right'), '', 'arm side'),
    'publish_tf': (False, prm.boolean, '', 'broadcast TF'),
}


def test_defaults_are_returned_and_validated():
    cfg = prm.read({}, SPEC)
    assert cfg == {'rate': 30.0, 'host': '127.0.0.1', 'port': 5001, 'timeout': 0.1, 'side': 'left',
                   'publish_tf': False}


def test_given_values_win_and_ints_become_floats_for_float_rules():
    cfg = prm.read({'rate': 100, 'timeout': 2, 'side': 'right', 'unknown': 'ignored'}, SPEC)
    assert cfg['rate'] == 100.0 and isinstance(cfg['rate'], float)
    assert cfg['timeout'] == 2.0 and isinstance(cfg['timeout'], float)
    assert cfg['side'] == 'right' and 'unknown' not in cfg


def test_error_names_parameter_value_unit_rule_and_description():
    with pytest.raises(prm.ParamError) as err:
        prm.read({'rate': -3.0}, SPEC)
    msg = str(err.value)
    assert '~rate' in msg and '-3.0' in msg and '[Hz]' in msg
    assert '(0, 1000]' in msg and 'publication rate' in msg


@pytest.mark.parametrize('name, value', [
    ('rate', 0.0), ('rate', 1000.5), ('rate', float('nan')), ('rate', 'fast'), ('rate', True),
    ('host', ''), ('host', 5), ('port', 70000), ('port', -1), ('port', 5001.0), ('timeout', 0),
    ('timeout', float('inf')), ('side', 'middle'), ('publish_tf', 1),
])
def test_invalid_values_are_rejected(name, value):
    with pytest.raises(prm.ParamError, match='~%s' % name):
        prm.read({name: value}, SPEC)


def test_required_parameter_missing_is_an_error_naming_it():
    spec = {'file': (prm.REQUIRED, prm.non_empty_text, '', 'frames YAML path')}
    with pytest.raises(prm.ParamError, match='~file.*required.*frames YAML path'):
        prm.read({}, spec)
    assert prm.read({'file': 'a.yaml'}, spec) == {'file': 'a.yaml'}


def test_values_must_be_a_mapping():
    with pytest.raises(prm.ParamError, match='mapping'):
        prm.read(['rate'], SPEC)


def test_numeric_rules():
    assert prm.finite(-1.5) and not prm.finite(float('inf')) and not prm.finite(False)
    assert prm.non_negative(0) and not prm.non_negative(-1e-9)
    assert prm.positive_integer(3) and not prm.positive_integer(0) and not prm.positive_integer(3.0)
    assert prm.non_negative_integer(0) and not prm.non_negative_integer(-1)
    assert prm.at_least(3, integral=True)(3) and not prm.at_least(3, integral=True)(2)
    assert prm.at_most(1.0)(1.0) and not prm.at_most(1.0)(1.01)
    r = prm.in_range(0.0, 1.0, low_open=True, high_open=True)
    assert r(0.5) and not r(0.0) and not r(1.0)
    assert 'number in (0, 1)' in r.text


def test_vector_and_list_rules_convert():
    spec = {'xyz': ([0, 0, 0], prm.vector(3), 'm', 'position'),
            'dots': ([0, 1, 2], prm.list_of(prm.non_negative_integer, min_len=3, unique=True), '', 'dot ids')}
    cfg = prm.read({'xyz': [1, 2, 3]}, spec)
    assert cfg['xyz'] == [1.0, 2.0, 3.0] and all(isinstance(v, float) for v in cfg['xyz'])
    for bad in ([1, 2], [1, 2, float('nan')], 'abc', [1, 2, 'x']):
        with pytest.raises(prm.ParamError, match='~xyz.*list of 3 finite numbers'):
            prm.read({'xyz': bad}, spec)
    with pytest.raises(prm.ParamError, match='distinct'):
        prm.read({'dots': [1, 1, 2]}, spec)
    with pytest.raises(prm.ParamError, match='at least 3'):
        prm.read({'dots': [1, 2]}, spec)


def test_optional_all_of_and_parsed():
    def board(v):
        w, h = (int(x) for x in str(v).split('x'))
        if w < 2 or h < 2:
            raise ValueError('need at least 2x2 corners')
        return w, h
    spec = {'size': ('8x6', prm.parsed(board, 'WxH inner corners'), '', 'checkerboard'),
            'pa_joints': ([], prm.optional(prm.vector(7), none=([],)), 'rad', 'set-up joints'),
            'square': (0.008, prm.all_of(prm.positive, prm.at_most(1.0)), 'm', 'square side')}
    assert prm.read({}, spec) == {'size': (8, 6), 'pa_joints': [], 'square': 0.008}
    assert prm.read({'pa_joints': [0] * 7}, spec)['pa_joints'] == [0.0] * 7
    with pytest.raises(prm.ParamError, match=r'~size.*WxH inner corners \(need at least 2x2 corners\)'):
        prm.read({'size': '1x6'}, spec)
    with pytest.raises(prm.ParamError, match='~pa_joints'):
        prm.read({'pa_joints': [0] * 6}, spec)
    with pytest.raises(prm.ParamError, match=r'~square.*\[m\].*<= 1|~square.*\[m\].*1\]'):
        prm.read({'square': 2.0}, spec)


def test_plain_callables_are_accepted_with_their_docstring_as_rule():
    def even(v):
        """an even integer"""
        return isinstance(v, int) and v % 2 == 0
    spec = {'n': (2, even, '', 'count'), 'k': (1, lambda v: v > 0, '', 'other')}
    assert prm.read({'n': 4}, spec)['n'] == 4
    with pytest.raises(prm.ParamError, match='an even integer'):
        prm.read({'n': 3}, spec)
    with pytest.raises(prm.ParamError, match='custom check'):
        prm.read({'k': -1}, spec)


def test_invalid_builds_the_same_text_for_cross_parameter_checks():
    err = prm.invalid('backoff_max', 0.1, '>= ~backoff_initial (0.2)', 's', 'largest reconnection delay')
    assert isinstance(err, prm.ParamError)
    assert str(err) == ('parameter ~backoff_max = 0.1 [s] is invalid: must be >= ~backoff_initial (0.2)'
                        ' -- largest reconnection delay')


def test_where_prefix_is_used():
    with pytest.raises(prm.ParamError, match='/node/rate'):
        prm.read({'rate': math.nan}, SPEC, where='/node/')
