"""Report: foot-pedal events of the da Vinci console become pressed intervals on the trajectory plot."""
import matplotlib
matplotlib.use('Agg')
from geometry_msgs.msg import PoseStamped  # noqa: E402
from sensor_msgs.msg import Joy  # noqa: E402

from saras_bringup import report  # noqa: E402


def joy(v):
    return Joy(buttons=[v])


def test_pedal_intervals_pair_press_and_release():
    series = [(1.0, joy(0)), (2.0, joy(1)), (3.5, joy(0)), (5.0, joy(1))]
    assert report.pedal_intervals(series, 9.0) == [(2.0, 3.5), (5.0, 9.0)]
    assert report.pedal_intervals([], 9.0) == []


def test_console_plot_draws_pedal_spans():
    poses = [(t * 0.1, PoseStamped()) for t in range(20)]
    data = {'/dvrk/MTMR/position_cartesian_current': poses,
            '/dvrk/PSM1/position_cartesian_current': poses,
            '/dvrk/footpedals/clutch': [(0.5, joy(1)), (1.0, joy(0))]}
    fig = report.plot_console(data, 0.0)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert 'clutch pressed' in labels
    assert report.plot_console({}, 0.0) is None
