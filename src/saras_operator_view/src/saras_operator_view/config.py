"""Parameters of the operator view node (config/operator_view.yaml), validated once at start-up."""
import ipaddress
import re

from saras_common import params as prm


def _address(value):
    if not isinstance(value, str):
        raise TypeError('not a string')
    return str(ipaddress.ip_address(value))


_COLOUR = prm.Rule('colour "#rrggbb"', lambda v: isinstance(v, str) and re.fullmatch('#[0-9a-fA-F]{6}', v) is not None)
_TOPIC = prm.Rule('absolute ROS topic name', lambda v: isinstance(v, str) and re.fullmatch(r'(/[A-Za-z][\w]*)+', v)
                  is not None)

SPEC = {
    'bind_address': ('127.0.0.1', prm.parsed(_address, 'IPv4/IPv6 address (127.0.0.1: this host only)'), '',
                     'address the HTTP server binds'),
    'port': (8090, prm.port, '', 'TCP port of the page (0: any free port)'),
    'allowed_hosts': ([], prm.list_of(prm.non_empty_text, 0, 32), '',
                      'host names (DNS) a browser may use for the page besides the addresses; others get 403'),
    'title': ('SARAS operator view', prm.non_empty_text, '', 'page title'),
    'update_rate': (5.0, prm.in_range(0.0, 50.0, low_open=True), 'Hz', 'distances/energies/health pushes per client'),
    'max_stream_rate': (30.0, prm.in_range(0.0, 120.0, low_open=True), 'Hz', 'image frames per stream at most'),
    'max_clients': (8, prm.in_range(2, 64, integral=True), '', 'open image streams + event streams at most'),
    'client_timeout': (10.0, prm.in_range(0.5, 300.0), 's', 'a client that stops reading is dropped after this'),
    'stale_after': (2.0, prm.in_range(0.1, 60.0), 's', 'older distances, energies, health show as no data/STALE'),
    'collision_threshold': (0.005, prm.non_negative, 'm', 'distance <= this: collision colour'),
    'warning_threshold': (0.02, prm.positive, 'm', 'distance < this: warning colour'),
    'collision_colour': ('#ff0000', _COLOUR, '', 'tool in collision'),
    'warning_colour': ('#ffff00', _COLOUR, '', 'tool in the warning region'),
    'safe_colour': ('#00ff00', _COLOUR, '', 'tool away from every object'),
    'unknown_colour': ('#a0a0a0', _COLOUR, '', 'no distance (no data, stale or NaN)'),
    'left_image': ('/visual_feedback/left/image/compressed', _TOPIC, '', 'left augmented JPEG stream'),
    'right_image': ('/visual_feedback/right/image/compressed', _TOPIC, '', 'right augmented JPEG stream'),
    'distances': ('/collision/distances', _TOPIC, '', 'std_msgs/Float64MultiArray [mesa_left, mesa_right, PSM1, PSM2]'),
    'energies': (['/teleop/tank_master/energy', '/teleop/tank_slave/energy'], prm.list_of(_TOPIC, 1, 8, unique=True),
                 '', 'std_msgs/Float64 tank energies [J]'),
    'health': ('/diagnostics_agg', _TOPIC, '', 'diagnostic_aggregator output'),
}


def read(values):
    """Validated configuration from a parameter dict (ROS-free); raises prm.ParamError."""
    cfg = prm.read(values, SPEC)
    if not cfg['warning_threshold'] > cfg['collision_threshold']:
        raise prm.invalid('warning_threshold', cfg['warning_threshold'], '> collision_threshold (%g)'
                          % cfg['collision_threshold'], 'm')
    return cfg


def thresholds(cfg):
    return {'collision': cfg['collision_threshold'], 'warning': cfg['warning_threshold']}


def colours(cfg):
    return {k: cfg['%s_colour' % k] for k in ('collision', 'warning', 'safe', 'unknown')}


def tank_name(topic):
    """Display name of an energy topic: '/teleop/tank_master/energy' -> 'tank_master'."""
    parts = [p for p in topic.split('/') if p]
    return parts[-2] if len(parts) >= 2 and parts[-1] == 'energy' else topic
