"""saras_bringup.recording: recording list validation and the bag checker (rates, seq/stamp gaps).

The bags are written here with rosbag's Python API (no roscore), with known losses."""
import os

import pytest
import rosbag
import rospy
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Float64MultiArray

from saras_bringup.recording import (RecordingConfigError, check_bag, load_recording_config,
                                     parse_recording_config, recorder_command)

HERE = os.path.dirname(os.path.abspath(__file__))
SHIPPED = os.path.join(HERE, '..', 'config', 'recording.yaml')


def test_shipped_recording_list_covers_the_deliverable():
    cfg = load_recording_config(SHIPPED)
    groups = {s.group for s in cfg.streams}
    for g in ('endoscope video', 'da Vinci kinematics', 'SARAS kinematics', 'audio',
              'console commands', 'tf', 'collision', 'forces', 'tank energies'):
        assert g in groups
    # compressed video only: raw 1080p stereo would be ~373 MB/s
    assert not any(s.topic.endswith('image_raw') for s in cfg.streams)
    cmd = recorder_command(cfg, '/tmp/x.bag')
    assert cmd[:3] == ['rosrun', 'saras_bringup', 'bag_recorder']
    assert cmd[cmd.index('--buffsize') + 1] == str(cfg.buffer_mb)
    assert cmd[cmd.index('--queue') + 1] == str(cfg.queue) and cfg.queue >= 1000
    assert set(cfg.topics) <= set(cmd)
    assert ('--tcpnodelay' in cmd) == cfg.tcp_nodelay
    nodelay = parse_recording_config({'streams': [{'topic': '/a', 'rate': 1}], 'tcp_nodelay': True})
    assert '--tcpnodelay' in recorder_command(nodelay, '/tmp/x.bag')


@pytest.mark.parametrize('data, message', [
    ({'streams': []}, 'non-empty'),
    ({'streams': [{'topic': 'relative', 'rate': 1}]}, 'absolute'),
    ({'streams': [{'topic': '/a', 'rate': -1}]}, 'rate'),
    ({'streams': [{'topic': '/a', 'rate': 'fast'}]}, 'rate'),
    ({'streams': [{'topic': '/a', 'rate': 1}, {'topic': '/a', 'rate': 1}]}, 'twice'),
    ({'streams': [{'topic': '/a', 'rate': 1}], 'min_rate_fraction': 2}, 'min_rate_fraction'),
    ({'streams': [{'topic': '/a', 'rate': 1}], 'tcp_nodelay': 'yes'}, 'tcp_nodelay'),
])
def test_invalid_config(data, message):
    with pytest.raises(RecordingConfigError, match=message):
        parse_recording_config(data)


def write_bag(path, n=1000, rate=100.0, drop=(), dist_n=100):
    t0 = 1000.0
    with rosbag.Bag(path, 'w') as bag:
        for i in range(n):
            if i in drop:
                continue
            m = PoseStamped()
            m.header.seq = i + 1
            m.header.stamp = rospy.Time.from_sec(t0 + i / rate)
            bag.write('/pose', m, m.header.stamp)
        for i in range(dist_n):
            d = Float64MultiArray(data=[0.1, 0.2, 0.3, 0.4])
            bag.write('/dist', d, rospy.Time.from_sec(t0 + i / 20.0))


CFG = {'streams': [{'topic': '/pose', 'rate': 100, 'group': 'g'},
                   {'topic': '/dist', 'rate': 20, 'group': 'g', 'header': False},
                   {'topic': '/absent', 'rate': 10, 'group': 'g', 'required': True},
                   {'topic': '/optional', 'rate': 10, 'group': 'g', 'required': False}]}


def test_clean_bag_measures_rates(tmp_path):
    p = str(tmp_path / 'clean.bag')
    write_bag(p)
    results, problems = check_bag(p, parse_recording_config(CFG))
    rows = {r['topic']: r for r in results}
    assert rows['/pose']['count'] == 1000
    assert rows['/pose']['rate'] == pytest.approx(100.0, rel=1e-6)
    assert rows['/pose']['seq_gaps'] == 0 and rows['/pose']['stamp_gaps'] == 0
    assert rows['/dist']['rate'] == pytest.approx(20.0, rel=1e-6)
    assert problems == ['/absent (g): not recorded']    # the optional one is not a problem
    assert rows['/optional']['ok'] is False and rows['/optional']['required'] is False


def test_lost_messages_are_found(tmp_path):
    p = str(tmp_path / 'lossy.bag')
    write_bag(p, drop=set(range(100, 110)) | {500})
    results, problems = check_bag(p, parse_recording_config(CFG))
    row = [r for r in results if r['topic'] == '/pose'][0]
    assert row['seq_gaps'] == 11
    assert row['stamp_gaps'] == 1          # only the 10-message hole exceeds 3 periods
    assert any('/pose' in p and '11 messages lost' in p for p in problems)


def test_slow_stream_is_reported(tmp_path):
    p = str(tmp_path / 'slow.bag')
    write_bag(p, rate=50.0)   # nominal 100 Hz
    _, problems = check_bag(p, parse_recording_config(CFG))
    assert any('/pose' in p and 'below' in p for p in problems)
