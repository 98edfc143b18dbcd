"""Shared by the SARAS arm link tests (test_saras_arm_socketio.py, test_saras_arm_attacks.py):
the link key and arm of the tests, a set-up pose, a free loopback port and a polling wait."""
import time

from saras_simulation.bench_util import free_port  # noqa: F401 (re-exported for the link tests)

KEY = bytes(range(32))   # the arm link key of these tests
ARM = 'mesa_left'
#: A Positioning-Arm set-up pose [rad] (independent of saras_description's YAML).
PA = [0.0, 0.5, 0.0, 1.3, 0.0, 1.0, 0.0]


def wait_until(pred, timeout):
    """Polls ``pred`` every 10 ms for ``timeout`` s; its last value."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return pred()
