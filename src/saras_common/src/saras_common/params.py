"""Start-up parameters of the SARAS Python nodes: read once, typed, validated, with units.

A node declares its parameters as a spec ``{name: (default, rule, unit, description)}`` and reads
them all at start-up::

    SPEC = {
        'rate': (30.0, prm.in_range(0.0, 1000.0, low_open=True), 'Hz', 'publication rate'),
        'host': ('127.0.0.1', prm.non_empty_text, '', 'robot address'),
        'file': (prm.REQUIRED, prm.non_empty_text, '', 'frames YAML path'),
    }
    cfg = prm.read_or_exit('my_node', SPEC)        # dict name -> value, or fatal log + exit 2

:func:`read` is the ROS-free core (takes a dict, e.g. ``rospy.get_param('~', {})``), so a spec is
testable with pytest without a ROS master. A value that breaks its rule raises :class:`ParamError`
whose message names the parameter, the value, the unit, the rule and the description::

    parameter ~rate = -3.0 [Hz] is invalid: must be in (0, 1000] (publication rate)

Rules are :class:`Rule` objects (plain callables returning a bool are accepted too, their
docstring is the rule text). A rule may convert the value (``positive`` turns an int into a
float, :func:`parsed` applies a parser); the converted value is what :func:`read` returns.
Cross-parameter constraints are checked by the node after :func:`read`; :func:`invalid` builds
the same error text for them.
"""
import math
import sys

__all__ = [
    'ParamError', 'Rule', 'REQUIRED', 'read', 'invalid', 'read_ros', 'read_or_exit', 'fatal',
    'finite', 'positive', 'non_negative', 'integer', 'positive_integer', 'non_negative_integer',
    'port', 'text', 'non_empty_text', 'boolean', 'one_of', 'in_range', 'at_least', 'at_most',
    'vector', 'list_of', 'dictionary', 'optional', 'all_of', 'parsed',
]


class ParamError(ValueError):
    """A parameter value that the node cannot start with; the message says which and why."""


class _Required(object):
    def __repr__(self):
        return 'REQUIRED'


#: Default of a parameter that has no default: a missing value is a :class:`ParamError`.
REQUIRED = _Required()


class Rule(object):
    """A validation rule: ``test(value) -> bool``, a text for the error message and an optional
    ``convert(value) -> value`` applied first (it may raise ValueError/TypeError, whose text is
    added to the error)."""

    def __init__(self, text, test=None, convert=None):
        self.text = text
        self.test = test
        self.convert = convert

    def apply(self, value):
        """The converted value; raises ValueError (with a detail, possibly empty) if invalid."""
        if self.convert is not None:
            value = self.convert(value)
        if self.test is not None and not self.test(value):
            raise ValueError('')
        return value

    def __call__(self, value):
        try:
            self.apply(value)
        except (TypeError, ValueError):
            return False
        return True

    def __repr__(self):
        return 'Rule(%s)' % self.text


def _as_rule(check):
    if isinstance(check, Rule):
        return check
    text = (getattr(check, '__doc__', None) or '').strip() or getattr(check, '__name__', 'check')
    if text == '<lambda>':
        text = 'custom check'
    return Rule(text, test=check)


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _to_float(v):
    if not _is_number(v):
        raise TypeError('not a number')
    return float(v)


def _is_int(v):
    return isinstance(v, int) and not isinstance(v, bool)


def _fmt(x):
    return '%g' % x if _is_number(x) else repr(x)


finite = Rule('finite number', math.isfinite, _to_float)
positive = Rule('finite number > 0', lambda v: math.isfinite(v) and v > 0, _to_float)
non_negative = Rule('finite number >= 0', lambda v: math.isfinite(v) and v >= 0, _to_float)
integer = Rule('integer', _is_int)
positive_integer = Rule('integer > 0', lambda v: _is_int(v) and v > 0)
non_negative_integer = Rule('integer >= 0', lambda v: _is_int(v) and v >= 0)
port = Rule('TCP/UDP port, integer in [0, 65535]', lambda v: _is_int(v) and 0 <= v <= 65535)
text = Rule('string', lambda v: isinstance(v, str))
non_empty_text = Rule('non-empty string', lambda v: isinstance(v, str) and v != '')
boolean = Rule('true or false', lambda v: isinstance(v, bool))
dictionary = Rule('mapping', lambda v: isinstance(v, dict))


def one_of(*options):
    """The value is one of ``options``."""
    return Rule('one of %s' % ', '.join(repr(o) for o in options), lambda v: v in options)


def in_range(low=None, high=None, low_open=False, high_open=False, integral=False):
    """A finite number (an int if ``integral``) in the interval; ``None`` leaves a side open."""
    lo = '-inf' if low is None else _fmt(low)
    hi = 'inf' if high is None else _fmt(high)
    desc = '%s in %s%s, %s%s' % ('integer' if integral else 'number', '(' if low_open or low is None else '[',
                                 lo, hi, ')' if high_open or high is None else ']')

    def test(v):
        if not math.isfinite(v):
            return False
        if low is not None and (v < low or (low_open and v == low)):
            return False
        return high is None or (v < high or (not high_open and v == high))

    if integral:
        return Rule(desc, lambda v: _is_int(v) and test(v))
    return Rule(desc, test, _to_float)


def at_least(low, integral=False):
    """A finite number (int if ``integral``) >= ``low``."""
    return in_range(low, None, integral=integral)


def at_most(high, integral=False):
    """A finite number (int if ``integral``) <= ``high``."""
    return in_range(None, high, integral=integral)


def vector(n, allow_non_finite=False):
    """A list of ``n`` numbers (returned as a list of floats)."""
    def convert(v):
        if not isinstance(v, (list, tuple)) or len(v) != n:
            raise ValueError('')
        out = [_to_float(x) for x in v]
        if not allow_non_finite and not all(math.isfinite(x) for x in out):
            raise ValueError('')
        return out
    return Rule('list of %d %snumbers' % (n, '' if allow_non_finite else 'finite '), convert=convert)


def list_of(rule, min_len=0, max_len=None, unique=False):
    """A list whose items all satisfy ``rule`` (items converted by it)."""
    item = _as_rule(rule)
    size = ('at least %d ' % min_len if min_len else '') + ('at most %d ' % max_len if max_len is not None else '')

    def convert(v):
        if not isinstance(v, (list, tuple)) or len(v) < min_len or (max_len is not None and len(v) > max_len):
            raise ValueError('')
        out = [item.apply(x) for x in v]
        if unique and len(set(map(repr, out))) != len(out):
            raise ValueError('items repeat')
        return out
    return Rule('list of %s%s%s' % (size, 'distinct ' if unique else '', item.text), convert=convert)


def optional(rule, none=(None, '')):
    """``rule``, or one of the "not set" values ``none`` (returned as given)."""
    inner = _as_rule(rule)

    def convert(v):
        return v if any(v is n or (type(v) is type(n) and v == n) for n in none) else inner.apply(v)
    return Rule('%s, or unset (%s)' % (inner.text, ', '.join(repr(n) for n in none)), convert=convert)


def all_of(*rules):
    """Every rule in turn (conversions chain)."""
    rs = [_as_rule(r) for r in rules]

    def convert(v):
        for r in rs:
            v = r.apply(v)
        return v
    return Rule(' and '.join(r.text for r in rs), convert=convert)


def parsed(parser, description):
    """The value as returned by ``parser(value)``; the parser raises ValueError/TypeError (its
    message is part of the error) if the value is malformed."""
    return Rule(description, convert=parser)


def invalid(name, value, rule, unit='', description='', where='~', detail=''):
    """The :class:`ParamError` for parameter ``where + name`` holding ``value``."""
    msg = 'parameter %s%s = %r%s is invalid: must be %s' % (where, name, value, ' [%s]' % unit if unit else '', rule)
    if detail:
        msg += ' (%s)' % detail
    if description:
        msg += ' -- %s' % description
    return ParamError(msg)


def read(values, spec, where='~'):
    """Validated parameters ``{name: value}`` from the dict ``values`` (ROS-free).

    :param values: parameters as read (e.g. ``rospy.get_param('~', {})``); unknown keys ignored.
    :param spec: ``{name: (default, rule, unit, description)}``; ``default`` may be
        :data:`REQUIRED`. A missing value takes the default, which is validated like a given one.
    :param where: namespace shown in error messages.
    :raises ParamError: the first invalid or missing parameter, in spec order.
    """
    if not isinstance(values, dict):
        raise ParamError('parameters under %s must form a mapping, got %r' % (where, values))
    out = {}
    for name, entry in spec.items():
        default, check, unit, description = entry
        rule = _as_rule(check)
        if name not in values and default is REQUIRED:
            raise ParamError('parameter %s%s%s is required: %s (%s)' % (
                where, name, ' [%s]' % unit if unit else '', description, rule.text))
        value = values.get(name, default)
        try:
            out[name] = rule.apply(value)
        except (TypeError, ValueError) as exc:
            raise invalid(name, value, rule.text, unit, description, where, str(exc))
    return out


def read_ros(spec, namespace='~'):
    """:func:`read` over the parameter server's ``namespace`` (default: the node's private one);
    one ``get_param`` call, so every parameter is read exactly once."""
    import rospy
    where = namespace if namespace.endswith('/') or namespace == '~' else namespace + '/'
    return read(rospy.get_param(namespace, {}), spec, where)


def fatal(node, message, code=2):
    """Log a fatal start-up error (rospy.logfatal) and exit with status ``code``."""
    import rospy
    rospy.logfatal('%s: %s', node, message)
    sys.exit(code)


def read_or_exit(node, spec, namespace='~', code=2):
    """:func:`read_ros`, or :func:`fatal` with the :class:`ParamError` text."""
    try:
        return read_ros(spec, namespace)
    except ParamError as exc:
        fatal(node, str(exc), code)
