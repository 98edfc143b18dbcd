"""A recording replayed with replay.launch shows the augmented stereo in rviz: rviz runs headless
(Xvfb, software GL) on platform.rviz, both endoscope panels subscribe to the decoded images and the
recorded frames' colours appear on the screen (each eye at least once: rviz clears its displays when
the looped replay's clock jumps back, and software GL on a busy host repaints slowly). Starts its own master, Xvfb and roslaunch on free
ports/displays; a synthetic recording stands in for the platform's."""
import os
import shutil
import signal
import socket
import subprocess
import time

import cv2
import numpy as np
import pytest
import rosbag
import rospy
from sensor_msgs.msg import CompressedImage

rosgraph = pytest.importorskip('rosgraph')
PIL_ImageGrab = pytest.importorskip('PIL.ImageGrab')

COLOURS = {'left': (30, 160, 30), 'right': (160, 30, 200)}     # RGB of each eye's frames
TIMEOUT = 180.0


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def write_recording(path, seconds=60.0, rate=5.0):
    with rosbag.Bag(path, 'w') as bag:
        for i in range(int(seconds * rate)):
            stamp = rospy.Time.from_sec(1000.0 + i / rate)
            for eye, rgb in COLOURS.items():
                img = np.full((180, 320, 3), rgb[::-1], np.uint8)
                msg = CompressedImage(format='bgr8; jpeg compressed bgr8', data=cv2.imencode('.jpg', img)[1].tobytes())
                msg.header.seq, msg.header.stamp = i + 1, stamp
                bag.write('/visual_feedback/%s/image/compressed' % eye, msg, stamp)


def stop(proc):
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def subscribers(master, topic):
    _, subs, _ = master.getSystemState()
    return [n for t, nodes in subs if t == topic for n in nodes]


def screen_pixels(display, rgb, tol=12):
    grab = np.asarray(PIL_ImageGrab.grab(xdisplay=display).convert('RGB')).astype(int)
    return int(np.count_nonzero(np.all(np.abs(grab - np.array(rgb)) <= tol, axis=2)))


@pytest.mark.skipif(shutil.which('Xvfb') is None or shutil.which('rviz') is None, reason='needs Xvfb and rviz')
def test_replayed_augmented_stereo_shows_in_rviz(tmp_path):
    bag = str(tmp_path / 'augmented.bag')
    write_recording(bag)
    display = ':%d' % (200 + os.getpid() % 300)
    port = free_port()
    env = dict(os.environ, DISPLAY=display, LIBGL_ALWAYS_SOFTWARE='1', ROS_MASTER_URI='http://127.0.0.1:%d' % port,
               ROS_HOSTNAME='127.0.0.1', ROS_HOME=str(tmp_path / 'ros'))
    xvfb = subprocess.Popen(['Xvfb', display, '-screen', '0', '1600x1000x24', '-nolisten', 'tcp'],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    log = open(str(tmp_path / 'replay.log'), 'wb')
    launch = subprocess.Popen(['roslaunch', '-p', str(port), 'saras_bringup', 'replay.launch', 'bag:=' + bag],
                              env=env, stdout=log, stderr=subprocess.STDOUT)
    try:
        master = rosgraph.Master('/test_replay_rviz', master_uri=env['ROS_MASTER_URI'])
        deadline = time.monotonic() + TIMEOUT
        topics = ['/visual_feedback/%s/image' % eye for eye in COLOURS]
        shown = {}
        while time.monotonic() < deadline and launch.poll() is None:
            time.sleep(1.0)
            try:
                if not all('/rviz' in subscribers(master, t) for t in topics):
                    continue
            except (OSError, rosgraph.MasterException):
                continue
            for eye, rgb in COLOURS.items():
                shown[eye] = max(shown.get(eye, 0), screen_pixels(display, rgb))
            if len(shown) == len(COLOURS) and min(shown.values()) > 2000:
                break
        alive = launch.poll() is None
    finally:
        stop(launch)
        xvfb.terminate()
        xvfb.wait(20)
        log.close()
    text = open(str(tmp_path / 'replay.log'), errors='replace').read()
    assert alive, 'replay stopped:\n' + text[-3000:]
    assert len(shown) == len(COLOURS) and min(shown.values()) > 2000, 'augmented frames not on the screen (most pixels %s):\n%s' % (
        shown, text[-3000:])
