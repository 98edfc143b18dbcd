"""Stamp skew per publishing machine (saras_bringup.stamp_skew) and bag_check --machines on a bag
with one machine's stamps shifted."""
import json
import os
import subprocess
import sys

import pytest

from saras_bringup.stamp_skew import SkewSamples, flag_machines, machine_skews

HERE = os.path.dirname(os.path.abspath(__file__))
NODES = {'/dvrk/dvrk_sim': 'dvrk_pc', '/endoscope/endoscope_sim': 'dvrk_pc',
         '/teleop/teleop_manager': 'teleop_pc', '/mesa_left/saras_arms_state': 'teleop_pc'}


def test_samples_low_quantile_and_thinning():
    s = SkewSamples(max_samples=100)
    for i in range(1000):
        s.add(10.0 + i * 1e-3 + 0.004 + (0.03 if (i + 1) % 10 else 0.0), 10.0 + i * 1e-3)
    assert s.low(0.05) == pytest.approx(0.004, abs=1e-9)  # the 10 % fastest messages
    assert s.low(0.5) == pytest.approx(0.034, abs=1e-9)
    assert 50 <= len(s.values) <= 100
    assert SkewSamples().low() is None


def test_machine_skew_is_its_lowest_stream_and_flags_the_shifted_one():
    topic_skews = {'/dvrk/PSM1/a': -0.047, '/dvrk/PSM2/a': -0.048, '/endoscope/left/c': -0.030,
                   '/teleop/left/master_pose': 0.002, '/mesa_left/ee_pose': 0.004}
    pubs = {'/dvrk/PSM1/a': ['/dvrk/dvrk_sim'], '/dvrk/PSM2/a': ['/dvrk/dvrk_sim'],
            '/endoscope/left/c': ['/endoscope/endoscope_sim'],
            '/teleop/left/master_pose': ['/teleop/teleop_manager'], '/mesa_left/ee_pose': ['/mesa_left/saras_arms_state']}
    per = machine_skews(topic_skews, pubs, NODES)
    assert per['dvrk_pc']['skew_ms'] == pytest.approx(-48.0)
    assert per['teleop_pc']['skew_ms'] == pytest.approx(2.0)
    problems = flag_machines(per, 20.0)
    assert len(problems) == 1 and 'dvrk_pc' in problems[0] and 'ahead' in problems[0]
    assert flag_machines(machine_skews({'/x': 0.08}, {'/x': ['/dvrk/dvrk_sim']}, NODES), 20.0)[0].count('behind') == 1


def test_ahead_limit_is_separate_from_the_latency_limit():
    per = machine_skews({'/a': -0.0034, '/b': 0.012}, {'/a': ['/dvrk/dvrk_sim'], '/b': ['/teleop/teleop_manager']}, NODES)
    assert flag_machines(per, 20.0) == []                  # symmetric 20 ms: a 3.4 ms lead passes
    problems = flag_machines(per, 20.0, 2.0)               # stamps 3.4 ms in the future: a clock ahead
    assert len(problems) == 1 and 'dvrk_pc' in problems[0] and 'ahead' in problems[0] and 'limit 2 ms' in problems[0]
    assert flag_machines(per, 10.0, 2.0)[1].startswith('machine teleop_pc')  # 12 ms late beyond 10 ms


def test_topic_from_two_machines_is_left_out():
    per = machine_skews({'/tf_like': -0.5}, {'/tf_like': ['/dvrk/dvrk_sim', '/teleop/teleop_manager']}, NODES)
    assert per == {}


def write_bag(path, offset_s):
    rosbag = pytest.importorskip('rosbag')
    import rospy
    from geometry_msgs.msg import PoseStamped
    with rosbag.Bag(path, 'w') as bag:
        for i in range(200):
            t = 100.0 + 0.01 * i
            for topic, caller, off in (('/dvrk/PSM1/position_cartesian_current', '/dvrk/dvrk_sim', offset_s),
                                       ('/mesa_left/ee_pose', '/mesa_left/saras_arms_state', 0.0)):
                m = PoseStamped()
                m.header.seq = i
                m.header.stamp = rospy.Time.from_sec(t - 0.002 + off)
                bag.write(topic, m, rospy.Time.from_sec(t), connection_header={
                    'callerid': caller, 'topic': topic, 'type': 'geometry_msgs/PoseStamped',
                    'md5sum': PoseStamped._md5sum, 'message_definition': PoseStamped._full_text})


@pytest.mark.parametrize('offset_s,flagged', [(0.0, False), (0.005, True), (0.05, True), (-0.005, False), (-0.08, True)])
def test_bag_check_flags_the_machine_with_shifted_stamps(tmp_path, offset_s, flagged):
    bag = str(tmp_path / 'skew.bag')
    write_bag(bag, offset_s)
    machines = tmp_path / 'machines.json'
    machines.write_text(json.dumps({'nodes': NODES}))
    out = tmp_path / 'check.json'
    script = os.path.join(HERE, '..', 'scripts', 'bag_check')
    r = subprocess.run([sys.executable, script, bag, '--machines', str(machines), '--json', str(out)],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    result = json.loads(out.read_text())
    dvrk = result['machines']['dvrk_pc']['skew_ms']
    assert dvrk == pytest.approx(2.0 - 1e3 * offset_s, abs=0.5)
    assert result['machines']['teleop_pc']['skew_ms'] == pytest.approx(2.0, abs=0.5)
    assert any('dvrk_pc' in p for p in result['problems']) == flagged, r.stdout
    assert not any('teleop_pc' in p for p in result['problems'])
