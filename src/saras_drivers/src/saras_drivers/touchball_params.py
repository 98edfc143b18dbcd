"""Start-up parameter validation shared by the Touchball and SARAS-arm nodes (ROS-agnostic).

A node builds a dict of parameters (rospy.get_param('~', {})) and calls :func:`read` with a
spec ``{name: (default, check, unit, description)}``. Missing values take the default; a value
that fails its check raises :class:`ParamError` naming the parameter, the unit and the value,
which the node turns into a fatal log line and a non-zero exit.
"""

import math


class ParamError(ValueError):
    pass


def finite(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def positive(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0


def non_negative(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0


def port(v):
    return isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 65535


def text(v):
    return isinstance(v, str)


def boolean(v):
    return isinstance(v, bool)


def one_of(*options):
    def check(v):
        return v in options
    check.__doc__ = 'one of %s' % (options,)
    return check


def vector(n, finite=True):
    def check(v):
        return (isinstance(v, (list, tuple)) and len(v) == n and
                all(isinstance(x, (int, float)) and not isinstance(x, bool) and
                    (math.isfinite(x) or not finite) for x in v))
    check.__doc__ = 'list of %d numbers' % n
    return check


def read(values, spec, where='~'):
    """Validated parameters: dict name -> value. Unknown extra keys are ignored."""
    out = {}
    for name, (default, check, unit, doc) in spec.items():
        v = values.get(name, default)
        if isinstance(default, float) and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        if not check(v):
            rule = check.__doc__ or check.__name__
            raise ParamError('parameter %s%s = %r is invalid: %s%s%s' % (
                where, name, v, doc, '' if rule == '<lambda>' else ' (%s)' % rule,
                ' [%s]' % unit if unit else ''))
        out[name] = v
    return out
