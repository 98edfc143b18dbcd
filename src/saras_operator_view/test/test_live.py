"""saras_operator_view.live: colour mapping, payload formatting, frame hand-off (no ROS)."""
import math
import threading

import pytest

from saras_operator_view.live import FrameSlot, LiveState, aggregator_groups, proximity

THR = {'collision': 0.005, 'warning': 0.02}
COL = {'collision': '#ff0000', 'warning': '#ffff00', 'safe': '#00ff00', 'unknown': '#a0a0a0'}


@pytest.mark.parametrize('d, region', [
    (-0.001, 'collision'), (0.005, 'collision'), (0.0051, 'warning'), (0.0199, 'warning'), (0.02, 'safe'),
    (0.5, 'safe'), (math.inf, 'safe'), (-math.inf, 'collision'), (math.nan, 'unknown'), (None, 'unknown')])
def test_proximity_matches_the_visual_feedback_overlay(d, region):
    # saras_visual_feedback overlay.cpp classify: <= collision, < warning, else safe; NaN unknown
    assert proximity(d, THR['collision'], THR['warning']) == region


def live():
    return LiveState(THR, COL, ['tank_master', 'tank_slave'], stale_after=2.0)


def test_payload_formats_distances_energies_health():
    s = live()
    s.set_distances([0.001, 0.01, 0.05, math.nan], now=10.0)
    s.set_energy('tank_master', 9.5, now=10.0)
    s.set_energy('unknown_tank', 1.0, now=10.0)   # not configured: ignored
    s.set_health([('Collision', 0, 'OK'), ('Teleoperation', 2, 'tank empty')], now=10.0)
    p = s.snapshot(now=10.5)
    assert [t['tool'] for t in p['tools']] == ['mesa_left', 'mesa_right', 'PSM1', 'PSM2']
    assert [t['region'] for t in p['tools']] == ['collision', 'warning', 'safe', 'unknown']
    assert [t['colour'] for t in p['tools']] == ['#ff0000', '#ffff00', '#00ff00', '#a0a0a0']
    assert [t['distance_mm'] for t in p['tools']] == [1.0, 10.0, 50.0, None]
    assert p['tanks'] == [{'tank': 'tank_master', 'energy_j': 9.5, 'age_s': 0.5},
                          {'tank': 'tank_slave', 'energy_j': None, 'age_s': None}]
    assert p['health'] == [{'name': 'Collision', 'level': 'OK', 'message': 'OK'},
                           {'name': 'Teleoperation', 'level': 'ERROR', 'message': 'tank empty'}]
    assert p['thresholds_mm'] == {'collision': 5.0, 'warning': 20.0}
    assert p['frames'] == {'left': {'count': 0, 'bytes': 0}, 'right': {'count': 0, 'bytes': 0}}


def test_stale_values_show_as_no_data():
    s = live()
    s.set_distances([0.001, 0.01, 0.05, 0.1], now=0.0)
    s.set_energy('tank_slave', 3.0, now=0.0)
    s.set_health([('Collision', 0, 'OK')], now=0.0)
    p = s.snapshot(now=5.0)
    assert all(t['region'] == 'unknown' and t['distance_mm'] is None for t in p['tools'])
    assert p['tanks'][1]['energy_j'] is None and p['tanks'][1]['age_s'] == 5.0
    assert p['health'][0]['level'] == 'STALE'


def test_short_or_non_finite_inputs_never_break_the_payload():
    s = live()
    s.set_distances([0.01], now=0.0)              # fewer than four tools
    s.set_energy('tank_master', math.inf, now=0.0)
    p = s.snapshot(now=0.1)
    assert [t['region'] for t in p['tools']] == ['warning', 'unknown', 'unknown', 'unknown']
    assert p['tanks'][0]['energy_j'] is None


def test_aggregator_groups_are_the_top_level_statuses():
    statuses = [('/Collision', 0, 'OK'), ('/Collision/colliding_regions: inputs', 0, 'x'),
                ('/SARAS arms', 1, 'Warning'), ('/SARAS arms/Left', 1, 'w'), ('/', 0, ''), ('Other', 0, '')]
    assert aggregator_groups(statuses) == [('Collision', 0, 'OK'), ('SARAS arms', 1, 'Warning')]


def test_frame_slot_hands_the_newest_jpeg_to_waiters():
    slot = FrameSlot()
    assert slot.wait_newer(0, 0.05) is None
    got = []
    t = threading.Thread(target=lambda: got.append(slot.wait_newer(0, 30.0)))
    t.start()
    slot.put(b'\xff\xd8one', 1.0)
    t.join(30.0)
    assert got == [(1, b'\xff\xd8one')]
    slot.put(b'\xff\xd8two', 2.0)
    slot.put(b'\xff\xd8three', 3.0)
    assert slot.wait_newer(1, 1.0) == (3, b'\xff\xd8three')   # a slow reader skips to the newest
    slot.close()
    assert slot.wait_newer(3, 30.0) is None                      # released at once on close
