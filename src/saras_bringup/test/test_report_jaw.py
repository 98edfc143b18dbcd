"""Report: the instrument jaw plot shows the Simball clip, the commanded and the measured jaw."""
import matplotlib
matplotlib.use('Agg')
from saras_msgs.msg import HapticDeviceState  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from saras_bringup import report  # noqa: E402


def joints(names, jaw):
    return JointState(name=names, position=[0.0] * (len(names) - 1) + [jaw])


def test_jaw_series_picks_the_named_joint():
    series = [(0.0, joints(['mesa_left/er_yaw', 'mesa_left/jaw'], 0.2)),
              (0.1, joints(['mesa_left/er_yaw'], 0.0)),                 # no jaw: skipped
              (0.2, joints(['mesa_left/jaw'], 0.4))]
    t, v = report._jaw(series, 'mesa_left/jaw')
    assert list(t) == [0.0, 0.2] and list(v) == [0.2, 0.4]


def test_jaw_plot_has_clip_command_and_measurement():
    data = {'/touchball/left/state': [(0.1 * k, HapticDeviceState(clip_angle=0.05 * k)) for k in range(10)],
            '/mesa_left/jaw_target': [(0.1 * k, joints(['mesa_left/jaw'], 0.04 * k)) for k in range(10)],
            '/mesa_left/joint_states': [(0.1 * k, joints(['mesa_left/er_yaw', 'mesa_left/jaw'], 0.03 * k))
                                        for k in range(10)]}
    fig = report.plot_jaw(data, 0.0)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert labels == ['Simball clip angle', 'commanded (jaw_target)', 'measured (joint_states)']
    assert report.plot_jaw({}, 0.0) is None
