"""The augmented stereo is recorded (JPEG) and a replay shows it in rviz: recording list, a synthetic
recording checked and decoded as the replay does, the rviz endoscope panels and replay.launch's
decoders (roslaunch's loader, no master)."""
import os

import cv2
import numpy as np
import pytest
import rosbag
import rospy
import yaml
from sensor_msgs.msg import CompressedImage

from saras_bringup.recording import check_bag, load_recording_config

roslaunch_config = pytest.importorskip('roslaunch.config')

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(HERE, '..', '..')
RECORDING = os.path.join(HERE, '..', 'config', 'recording.yaml')
RVIZ = os.path.join(SRC, 'saras_description', 'rviz', 'platform.rviz')
REPLAY = os.path.join(HERE, '..', 'launch', 'replay.launch')
EYES = ('left', 'right')
COMPRESSED = {eye: '/visual_feedback/%s/image/compressed' % eye for eye in EYES}
RAW = {eye: '/visual_feedback/%s/image' % eye for eye in EYES}


def test_augmented_stereo_is_a_required_recorded_stream():
    cfg = load_recording_config(RECORDING)
    streams = {s.topic: s for s in cfg.streams}
    for eye in EYES:
        s = streams[COMPRESSED[eye]]
        assert s.required and s.rate == 30.0 and s.header
        assert RAW[eye] not in streams          # raw 2x 720p would be ~165 MB/s


def write_recording(path, seconds=2.0, rate=30.0):
    t0 = 1000.0
    with rosbag.Bag(path, 'w') as bag:
        for i in range(int(seconds * rate)):
            stamp = rospy.Time.from_sec(t0 + i / rate)
            for k, eye in enumerate(EYES):
                img = np.full((36, 64, 3), (i % 256, 40 * k, 200), np.uint8)
                msg = CompressedImage(format='bgr8; jpeg compressed bgr8', data=cv2.imencode('.jpg', img)[1].tobytes())
                msg.header.seq = i + 1
                msg.header.stamp = stamp
                bag.write(COMPRESSED[eye], msg, stamp)


def test_recorded_augmented_frames_pass_the_check_and_decode(tmp_path):
    path = str(tmp_path / 'augmented.bag')
    write_recording(path)
    results, _ = check_bag(path, load_recording_config(RECORDING))
    rows = {r['topic']: r for r in results}
    for eye in EYES:
        row = rows[COMPRESSED[eye]]
        assert row['ok'] and row['count'] == 60 and row['type'] == 'sensor_msgs/CompressedImage'
        assert row['rate'] == pytest.approx(30.0, rel=0.05)
    decoded = 0
    with rosbag.Bag(path) as bag:
        for _, msg, _ in bag.read_messages(topics=list(COMPRESSED.values())):
            img = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_COLOR)
            assert img is not None and img.shape == (36, 64, 3)
            decoded += 1
    assert decoded == 120


def rviz_images():
    with open(RVIZ) as f:
        doc = yaml.safe_load(f)
    return [d for d in doc['Visualization Manager']['Displays'] if d.get('Class') == 'rviz/Image']


def test_rviz_shows_both_augmented_eyes():
    panels = {d['Image Topic']: d for d in rviz_images()}
    for eye in EYES:
        d = panels[RAW[eye]]
        assert d['Enabled'] and d['Value']
        # raw: the image_transport 'compressed' plugin is not packaged in Debian 12; live, the
        # nodelet publishes raw, and on replay replay.launch decodes the recorded JPEG (below)
        assert d['Transport Hint'] == 'raw'


def test_replay_decodes_the_recorded_jpeg_for_rviz():
    cfg = roslaunch_config.load_config_default([(REPLAY, ['bag:=/tmp/x.bag'])], None, verbose=False)
    decoders = {}
    for n in cfg.nodes:
        if (n.package, n.type) == ('saras_operator_view', 'jpeg_to_raw'):
            remap = dict(n.remap_args)
            decoders[remap['in']] = remap['out']
    assert decoders == {COMPRESSED[eye]: RAW[eye] for eye in EYES}
    assert {d['Image Topic'] for d in rviz_images()} >= set(decoders.values())
    assert any(n.type == 'rviz' for n in cfg.nodes) and any(n.type == 'play' for n in cfg.nodes)


@pytest.mark.parametrize('extra, bags', [
    ([], ['/tmp/x.bag']),
    (['extra_bags:=/tmp/x.teleop.bag /tmp/x.more.bag'], ['/tmp/x.bag', '/tmp/x.teleop.bag', '/tmp/x.more.bag'])])
def test_replay_plays_the_recording_and_its_extra_bags(extra, bags):
    cfg = roslaunch_config.load_config_default([(REPLAY, ['bag:=/tmp/x.bag'] + extra)], None, verbose=False)
    play = [n for n in cfg.nodes if (n.package, n.type) == ('rosbag', 'play')]
    assert len(play) == 1 and play[0].args.split()[-len(bags) - 1:] == ['1.0'] + bags
