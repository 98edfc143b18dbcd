"""saras_operator_view.config: the shipped YAML is valid and agrees with the visual feedback;
bad values are refused with the parameter's name."""
import os

import pytest
import yaml

from saras_common.params import ParamError
from saras_operator_view import config

HERE = os.path.dirname(os.path.abspath(__file__))
SHIPPED = os.path.join(HERE, '..', 'config', 'operator_view.yaml')
VISUAL_FEEDBACK = os.path.join(HERE, '..', '..', 'saras_visual_feedback', 'config', 'visual_feedback.yaml')


def shipped():
    with open(SHIPPED) as f:
        return yaml.safe_load(f)


def test_shipped_config_binds_loopback():
    cfg = config.read(shipped())
    assert cfg['bind_address'] == '127.0.0.1'
    assert [config.tank_name(t) for t in cfg['energies']] == ['tank_master', 'tank_slave']


def test_thresholds_and_colours_equal_the_visual_feedback_overlay():
    cfg = config.read(shipped())
    with open(VISUAL_FEEDBACK) as f:
        vf = yaml.safe_load(f)
    for key in ('collision_threshold', 'warning_threshold', 'collision_colour', 'warning_colour',
                'safe_colour', 'unknown_colour'):
        assert cfg[key] == vf[key], key


@pytest.mark.parametrize('key, value', [
    ('bind_address', 'everywhere'), ('bind_address', 5), ('port', 70000), ('port', -1), ('port', 'http'),
    ('update_rate', 0.0), ('max_clients', 1), ('max_clients', 2.5), ('collision_colour', 'red'),
    ('warning_threshold', 0.001), ('left_image', 'relative/topic'), ('energies', []),
    ('energies', ['/a/energy', '/a/energy']), ('client_timeout', float('nan')), ('allowed_hosts', 'or-display'),
    ('allowed_hosts', [''])])
def test_bad_values_are_refused_naming_the_parameter(key, value):
    data = shipped()
    data[key] = value
    with pytest.raises(ParamError, match=key):
        config.read(data)


def test_ipv6_and_any_address_are_accepted():
    data = shipped()
    data['bind_address'] = '::1'
    assert config.read(data)['bind_address'] == '::1'
    data['bind_address'] = '0.0.0.0'
    assert config.read(data)['bind_address'] == '0.0.0.0'
