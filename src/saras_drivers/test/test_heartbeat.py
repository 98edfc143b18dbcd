"""Core test of the /saras/status heartbeat policy."""
from saras_drivers.heartbeat import Heartbeat, OK, WARN


def test_heartbeat_period_and_change():
    hb = Heartbeat('x', period=1.0)
    assert hb.due(0.0)            # first
    hb.set(OK, 'fine')
    assert hb.due(0.1)            # change
    assert not hb.due(0.5)
    hb.set(OK, 'fine')
    assert not hb.due(0.9)        # no change
    assert hb.due(1.2)            # period
    hb.set(WARN, 'bad')
    assert hb.due(1.3)
    hb.input_ok(2.0)
    hb.input_rejected()
    assert hb.received == 1 and hb.rejected == 1 and hb.input_age(2.5) == 0.5
