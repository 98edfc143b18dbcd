"""saras_bringup.recording: recording list validation, the recorder's command lines, the bags of a
recording (main bag + in-process part) and the bag checker (rates, seq/stamp gaps).

The bags are written here with rosbag's Python API (no roscore), with known losses."""
import os
import subprocess
import sys

import pytest
import rosbag
import rospy
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Float64MultiArray

from saras_bringup.recording import (RecordingConfigError, check_bag, load_recording_config, open_bags,
                                     parse_recording_config, part_path, recorder_command, recording_bags,
                                     start_time, stream_recorder_command)

HERE = os.path.dirname(os.path.abspath(__file__))
SHIPPED = os.path.join(HERE, '..', 'config', 'recording.yaml')
RECORDER = os.path.join(HERE, '..', 'scripts', 'recorder')
IN_MANAGER = {'/touchball/%s/%s' % (s, t) for s in ('left', 'right') for t in ('state', 'buttons', 'wrench_cmd')}
IN_MANAGER |= {'/touchball/status', '/teleop/tank_master/energy', '/teleop/tank_slave/energy'}
IN_MANAGER |= {'/mesa_%s/%s' % (s, t) for s in ('left', 'right') for t in ('target_pose', 'jaw_target')}
IN_MANAGER |= {'/teleop/%s/master_pose' % s for s in ('left', 'right')}


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
    assert set(cfg.main_topics) <= set(cmd)
    assert ('--tcpnodelay' in cmd) == cfg.tcp_nodelay
    nodelay = parse_recording_config({'streams': [{'topic': '/a', 'rate': 1}], 'tcp_nodelay': True})
    assert '--tcpnodelay' in recorder_command(nodelay, '/tmp/x.bag')


def test_shipped_in_process_streams_go_to_the_teleop_part():
    cfg = load_recording_config(SHIPPED)
    assert (cfg.in_process_manager, cfg.in_process_part) == ('/teleop/teleop_manager', 'teleop')
    assert set(cfg.in_process_topics) == IN_MANAGER and len(cfg.in_process_topics) == 15
    assert set(cfg.main_topics) == set(cfg.topics) - IN_MANAGER
    main = recorder_command(cfg, '/tmp/x.bag')
    assert not IN_MANAGER & set(main) and set(cfg.main_topics) <= set(main)
    assert set(cfg.topics) <= set(recorder_command(cfg, '/tmp/x.bag', in_process=False))
    assert recorder_command(cfg, '/tmp/x.bag', ['/extra'])[-1] == '/extra'


IN_PROCESS = {'in_process': {'manager': '/ns/manager', 'part': 'fast'}, 'buffer_mb': 64, 'chunk_kb': 128,
              'streams': [{'topic': '/slow', 'rate': 1}, {'topic': '/a', 'rate': 1, 'in_process': True},
                          {'topic': '/b', 'rate': 1, 'in_process': True}]}


def test_stream_recorder_command():
    cfg = parse_recording_config(IN_PROCESS)
    assert [s.in_process for s in cfg.streams] == [False, True, True]
    assert stream_recorder_command(cfg, '/x/run.bag', 'rec') == [
        'rosrun', 'nodelet', 'nodelet', 'load', 'saras_bringup/StreamRecorder', '/ns/manager', '__name:=rec_fast',
        '_output:=/x/run.fast.bag', '_topics:=/a,/b', '_buffer_mb:=64', '_chunk_kb:=128']
    assert recorder_command(cfg, '/x/run.bag')[-1] == '/slow'
    with pytest.raises(RecordingConfigError):     # nothing to record in-process
        stream_recorder_command(parse_recording_config({'streams': [{'topic': '/a', 'rate': 1}]}), '/x.bag', 'r')


@pytest.mark.parametrize('output, part, expected', [
    ('/x/platform.bag', 'teleop', '/x/platform.teleop.bag'),
    ('/x.y/run', 'p1', '/x.y/run.p1.bag'),
    ('rel/a.bag.bag', 'p', 'rel/a.bag.p.bag')])
def test_part_path(output, part, expected):
    assert part_path(output, part) == expected


def test_recording_bags_are_the_main_bag_and_its_closed_parts(tmp_path):
    main = str(tmp_path / 'platform.bag')
    for name in ('platform.bag', 'platform.teleop.bag', 'platform.b.bag', 'platform.c.bag.active',
                 'platformx.d.bag', 'other.teleop.bag'):
        (tmp_path / name).write_bytes(b'')
    parts = [str(tmp_path / n) for n in ('platform.b.bag', 'platform.teleop.bag')]
    assert recording_bags(main) == [main] + parts
    cfg = load_recording_config(SHIPPED)
    assert recording_bags(main, cfg) == [main, str(tmp_path / 'platform.teleop.bag')]
    (tmp_path / 'platform.teleop.bag').unlink()
    assert recording_bags(main, cfg) == [main]
    assert recording_bags(main, parse_recording_config(CFG)) == [main]       # no in_process section


def test_recorder_prints_the_bags_of_a_recording(tmp_path):
    def bags(*flags):
        out = subprocess.run([sys.executable, RECORDER, '--config', SHIPPED, '--output', 'rel/p.bag',
                              '--print-bags', '__name:=rec'] + list(flags), cwd=str(tmp_path),
                             capture_output=True, text=True, check=True).stdout
        return out.split()
    main = str(tmp_path / 'rel' / 'p.bag')
    assert bags() == [main, str(tmp_path / 'rel' / 'p.teleop.bag')]
    assert bags('--no-in-process') == [main]
    bad = tmp_path / 'bad.yaml'
    bad.write_text('streams: [{topic: /a, rate: 1, in_process: true}]\n')
    rc = subprocess.run([sys.executable, RECORDER, '--config', str(bad), '--output', 'x.bag'],
                        capture_output=True, text=True)
    assert rc.returncode == 1 and '/a' in rc.stderr and 'in_process' in rc.stderr


@pytest.mark.parametrize('data, message', [
    ({'streams': []}, 'non-empty'),
    ({'streams': [{'topic': 'relative', 'rate': 1}]}, 'absolute'),
    ({'streams': [{'topic': '/a', 'rate': -1}]}, 'rate'),
    ({'streams': [{'topic': '/a', 'rate': 'fast'}]}, 'rate'),
    ({'streams': [{'topic': '/a', 'rate': 1}, {'topic': '/a', 'rate': 1}]}, 'twice'),
    ({'streams': [{'topic': '/a', 'rate': 1}], 'min_rate_fraction': 2}, 'min_rate_fraction'),
    ({'streams': [{'topic': '/a', 'rate': 1}], 'tcp_nodelay': 'yes'}, 'tcp_nodelay'),
    ({'streams': [{'topic': '/a', 'rate': 1, 'in_process': True}]}, r'streams\[0\] \(/a\).*"in_process" section'),
    (dict(IN_PROCESS, streams=[{'topic': '/a', 'rate': 1, 'in_process': 'yes'}]), r'\(/a\).*true or false'),
    (dict(IN_PROCESS, in_process=['/ns/manager', 'fast']), 'mapping'),
    (dict(IN_PROCESS, in_process={'manager': 'ns/manager', 'part': 'fast'}), 'manager'),
    (dict(IN_PROCESS, in_process={'manager': '/ns/manager/', 'part': 'fast'}), 'manager'),
    (dict(IN_PROCESS, in_process={'part': 'fast'}), 'manager'),
    (dict(IN_PROCESS, in_process={'manager': '/ns/manager', 'part': ''}), 'part'),
    (dict(IN_PROCESS, in_process={'manager': '/ns/manager', 'part': 'a.b'}), 'part'),
    (dict(IN_PROCESS, in_process={'manager': '/ns/manager'}), 'part'),
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


def write_split_bags(main, part, n=1000, rate=100.0):
    """/pose alternately into the main and the part bag (one topic in two bags), /dist in the part."""
    t0 = 1000.0
    with rosbag.Bag(main, 'w') as a, rosbag.Bag(part, 'w') as b:
        for i in range(n):
            m = PoseStamped()
            m.header.seq = i + 1
            m.header.stamp = rospy.Time.from_sec(t0 + i / rate)
            (a if i % 2 else b).write('/pose', m, m.header.stamp)
        for i in range(100):
            b.write('/dist', Float64MultiArray(data=[0.1]), rospy.Time.from_sec(t0 + i / 20.0))


def test_check_bag_reads_every_bag_of_a_recording(tmp_path):
    main, part = str(tmp_path / 'p.bag'), str(tmp_path / 'p.fast.bag')
    write_split_bags(main, part)
    cfg = parse_recording_config(CFG)
    rows = {r['topic']: r for r in check_bag(recording_bags(main), cfg)[0]}
    assert rows['/pose']['count'] == 1000 and rows['/pose']['seq_gaps'] == 0     # merged by receive time
    assert rows['/pose']['stamp_gaps'] == 0 and rows['/pose']['max_interval'] == pytest.approx(0.01)
    assert rows['/pose']['rate'] == pytest.approx(100.0, rel=1e-6)
    assert rows['/dist']['count'] == 100 and rows['/dist']['type'] == 'std_msgs/Float64MultiArray'
    only_main = {r['topic']: r for r in check_bag(main, cfg)[0]}
    assert only_main['/pose']['seq_gaps'] == 499 and only_main['/dist']['count'] == 0


def test_an_empty_part_bag_is_read_as_no_messages(tmp_path):
    main, part = str(tmp_path / 'p.bag'), str(tmp_path / 'p.fast.bag')
    write_bag(main)
    with rosbag.Bag(part, 'w'):
        pass
    rows = {r['topic']: r for r in check_bag([main, part], parse_recording_config(CFG))[0]}
    assert rows['/pose']['count'] == 1000
    with open_bags([part, main]) as bags:
        assert start_time(bags) == pytest.approx(1000.0)
    with open_bags(part) as bags:
        assert start_time(bags) is None
