"""saras_bringup.report.colour_occupancy: the visual feedback's colour per /collision/distances sample."""
import collections

import pytest

pytest.importorskip('matplotlib')
from saras_bringup.report import colour_occupancy, occupancy_html  # noqa: E402

Msg = collections.namedtuple('Msg', 'data')
THRESH = {'collision': 0.005, 'warning': 0.02}


def series(rows):
    return [(0.1 * i, Msg(r)) for i, r in enumerate(rows)]


def test_counts_follow_the_threshold_regions_boundaries_included():
    # mesa_left: 0.005 is red (<=), 0.0050001 and 0.02 yellow (<=), 0.0200001 green; NaN ignored
    rows = [[0.005, 0.1, 0.03, -0.002], [0.0050001, 0.1, 0.0, 0.1], [0.02, 0.1, 0.01, 0.1],
            [0.0200001, float('nan'), 0.05, 0.1], [-0.01, 0.2, 0.05, 0.1]]
    occ = colour_occupancy(series(rows), THRESH)
    assert occ['mesa_left'] == {'red': 2, 'yellow': 2, 'green': 1}
    assert occ['mesa_right'] == {'red': 0, 'yellow': 0, 'green': 4}
    assert occ['PSM1'] == {'red': 1, 'yellow': 1, 'green': 3}
    assert occ['PSM2'] == {'red': 1, 'yellow': 0, 'green': 4}
    assert 'all three colours occurred' in occupancy_html(occ)


def test_missing_colour_is_reported():
    occ = colour_occupancy(series([[0.1, 0.1], [0.01, 0.2]]), THRESH)
    assert set(occ) == {'mesa_left', 'mesa_right'}   # short arrays: absent tools are not invented
    text = occupancy_html(occ)
    assert 'never shown: red' in text and 'all three' not in text
