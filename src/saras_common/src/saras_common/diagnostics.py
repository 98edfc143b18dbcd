"""The diagnostic_updater of the SARAS Python nodes, without a parameter-server call every 250 ms.

rospy's ``diagnostic_updater.Updater`` re-reads ``~diagnostic_period`` four times a second with
``rospy.get_param_cached``, which caches only parameters that exist: while the parameter is unset,
every re-read is a synchronous XML-RPC round trip to the master (measured in a demo: ~4 calls/s per
node, 11 nodes, each call logged by rosmaster as ``+CACHEDPARAM``). :func:`updater` puts the period
on the parameter server first (the value already there wins), so the re-reads hit the local cache.
"""
import math

DEFAULT_PERIOD = 1.0    # [s] diagnostic_updater's own default


def ensure_period(param_api, default=DEFAULT_PERIOD):
    """Set ``~diagnostic_period`` [s] to ``default`` unless it is set; returns the period in force.
    ``param_api`` has ``has_param``, ``get_param``, ``set_param`` (rospy, or a test double)."""
    if not (math.isfinite(default) and default > 0.0):
        raise ValueError('diagnostic period must be > 0 s, got %r' % (default,))
    name = '~diagnostic_period'
    if param_api.has_param(name):
        return param_api.get_param(name)
    param_api.set_param(name, float(default))
    return float(default)


def updater(default_period=DEFAULT_PERIOD):
    """A ``diagnostic_updater.Updater`` of this node with its period on the parameter server."""
    import diagnostic_updater
    import rospy
    ensure_period(rospy, default_period)
    return diagnostic_updater.Updater()
