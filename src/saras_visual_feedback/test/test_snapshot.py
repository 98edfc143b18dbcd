"""visual_feedback_snapshot reads the augmented stereo of a recording: last pair, frame counts and the
warning colours drawn (JPEG-shifted), without a ROS master."""
import importlib.machinery
import importlib.util
import json
import os

import cv2
import numpy as np
import rosbag
import rospy
from sensor_msgs.msg import CameraInfo, CompressedImage

SCRIPT = os.path.join(os.path.dirname(__file__), '..', 'scripts', 'visual_feedback_snapshot')


def load_tool():
    loader = importlib.machinery.SourceFileLoader('visual_feedback_snapshot', SCRIPT)
    spec = importlib.util.spec_from_loader(loader.name, loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def frame(bgr_marks, shade):
    img = np.full((120, 160, 3), shade, np.uint8)        # tissue-like background
    for i, bgr in enumerate(bgr_marks):
        cv2.circle(img, (30 + 45 * i, 60), 12, bgr, 3)     # a warning ring per colour
    msg = CompressedImage(format='bgr8; jpeg compressed bgr8', data=cv2.imencode('.jpg', img)[1].tobytes())
    return msg


def write_bag(path, n=20):
    red, yellow = (0, 0, 255), (0, 255, 255)
    with rosbag.Bag(path, 'w') as bag:
        for i in range(n):
            t = rospy.Time.from_sec(100 + i / 30.0)
            marks = [yellow] + ([red] if i >= n // 2 else [])   # red only in the second half, never green
            for eye, shade in (('left', (60, 70, 150)), ('right', (50, 60, 140))):
                msg = frame(marks, shade)
                msg.header.stamp = t
                bag.write('/visual_feedback/%s/image/compressed' % eye, msg, t)
                bag.write('/endoscope/%s/camera_info' % eye, CameraInfo(), t)


def test_census_and_pair(tmp_path):
    tool = load_tool()
    bag = str(tmp_path / 'run.bag')
    write_bag(bag)
    out = str(tmp_path / 'vf')
    assert tool.main([bag, '--output', out, '--every', '1']) == 0
    summary = json.load(open(out + '.json'))
    assert summary['frames_in'] == {'left': 20, 'right': 20}
    assert summary['frames_out'] == {'left': 20, 'right': 20}
    assert summary['frames_with_colour'] == {'collision': 10, 'warning': 20, 'safe': 0}
    assert summary['all_colours_seen'] is False
    pair = cv2.imread(out + '.png')
    assert pair.shape == (120, 320, 3)


def test_no_augmented_stream_is_an_error(tmp_path):
    tool = load_tool()
    bag = str(tmp_path / 'empty.bag')
    with rosbag.Bag(bag, 'w') as b:
        b.write('/endoscope/left/camera_info', CameraInfo(), rospy.Time(1))
    assert tool.main([bag, '--output', str(tmp_path / 'vf')]) == 1
    assert not os.path.exists(str(tmp_path / 'vf.png'))
