#!/usr/bin/env python3
"""rostest of the stereo capture nodelet (saras_drivers/StereoCapture), one scenario per .test:

capture (test/stereo_capture.test): two live 30 fps videotestsrc pipelines. Both eyes publish
  image_raw at >= 50 % of 30 Hz (measured from arrival counts over DURATION s; a busy 2-core host
  may slow the sources, it never speeds them up: <= 150 %); every left stamp is also a right stamp
  (pairs share one stamp; >= 90 % of the left frames, the first and last may be cut); camera_info
  equals the calibration YAML (size, D, K, R, P, frame) and carries the images' stamps;
  image_raw/compressed (the recorded stream) carries the same frames; /diagnostics has the node's "capture"
  status at OK with hardware_id endoscope, and its rate statuses.
broken (test/stereo_capture_broken.test): the left pipeline names a missing element. The node stays
  up: /diagnostics reports ERROR "left camera not open" naming the element, repeatedly over
  DURATION s with a growing open-failure count; the right eye's frames are counted as unmatched;
  no image is published.
Images are read as raw bytes (rospy.AnyMsg; stamp at byte 4): no deserialisation of 690 kB frames.
"""
import os
import struct
import sys
import threading
import time
import unittest

import rospy
import rostest
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from sensor_msgs.msg import CameraInfo

NODE = '/endoscope/stereo_capture'
EYES = ('left', 'right')
RATE = 30.0
DURATION = 6.0
STAMP = struct.Struct('<II')


class Recorder(object):
    """Arrival times and header stamps of one topic."""

    def __init__(self, topic, msg_class=rospy.AnyMsg):
        self.lock = threading.Lock()
        self.arrivals, self.stamps, self.last = [], [], None
        self.sub = rospy.Subscriber(topic, msg_class, self._on, queue_size=5, buff_size=1 << 24)

    def _on(self, msg):
        if isinstance(msg, rospy.AnyMsg):
            secs, nsecs = STAMP.unpack_from(msg._buff, 4)
        else:
            secs, nsecs = msg.header.stamp.secs, msg.header.stamp.nsecs
        with self.lock:
            self.arrivals.append(time.monotonic())
            self.stamps.append((secs, nsecs))
            self.last = msg

    def snapshot(self):
        with self.lock:
            return list(self.arrivals), list(self.stamps), self.last


class Diagnostics(object):
    """The node's /diagnostics statuses: {name: [(status, {key: value})]}."""

    def __init__(self):
        self.lock = threading.Lock()
        self.statuses = {}
        self.sub = rospy.Subscriber('/diagnostics', DiagnosticArray, self._on, queue_size=50)

    def _on(self, msg):
        for st in msg.status:
            if NODE.lstrip('/') in st.name:
                with self.lock:
                    self.statuses.setdefault(st.name.split(': ')[-1], []).append(
                        (st, {kv.key: kv.value for kv in st.values}))

    def get(self, task):
        with self.lock:
            return list(self.statuses.get(task, []))


def wait_until(predicate, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end and not rospy.is_shutdown():
        if predicate():
            return True
        time.sleep(0.1)
    return predicate()


class StereoCaptureTest(unittest.TestCase):

    def setUp(self):
        self.images = {e: Recorder('/endoscope/%s/image_raw' % e) for e in EYES}
        self.infos = {e: Recorder('/endoscope/%s/camera_info' % e, CameraInfo) for e in EYES}
        self.jpeg = Recorder('/endoscope/left/image_raw/compressed')
        self.diagnostics = Diagnostics()

    def test_scenario(self):
        scenario = rospy.get_param('~scenario')
        if scenario == 'capture':
            self.check_capture()
        else:
            self.check_broken()

    def check_capture(self):
        self.assertTrue(wait_until(lambda: all(self.images[e].snapshot()[0] for e in EYES), 60.0),
                        'no image from one of the eyes within 60 s')
        start = {e: len(self.images[e].snapshot()[0]) for e in EYES}
        time.sleep(DURATION)
        for e in EYES:
            arrivals, _, _ = self.images[e].snapshot()
            n = len(arrivals) - start[e]
            rate = n / DURATION
            rospy.loginfo('%s image_raw: %d frames in %.1f s = %.1f Hz', e, n, DURATION, rate)
            self.assertGreaterEqual(rate, 0.5 * RATE, '%s image_raw at %.1f Hz' % (e, rate))
            self.assertLessEqual(rate, 1.5 * RATE, '%s image_raw at %.1f Hz' % (e, rate))
        left = set(self.images['left'].snapshot()[1])
        right = set(self.images['right'].snapshot()[1])
        common = left & right
        rospy.loginfo('pairs: %d left stamps, %d right stamps, %d common', len(left), len(right), len(common))
        self.assertGreaterEqual(len(common), 0.9 * len(left) - 2,
                                '%d of %d left stamps are right stamps' % (len(common), len(left)))
        self.check_camera_info()
        # the recorded stream: image_transport's compressed plugin if installed, else the node's own
        jpeg = set(self.jpeg.snapshot()[1])
        self.assertGreater(len(jpeg), 10, 'left image_raw/compressed: %d messages' % len(jpeg))
        self.assertGreaterEqual(len(jpeg & left), 0.9 * len(jpeg) - 2, 'compressed stamps are not the images\'')
        self.assertTrue(wait_until(lambda: any(st.level == DiagnosticStatus.OK
                                               for st, _ in self.diagnostics.get('capture')), 20.0),
                        'no OK capture status: %s' % [st.message for st, _ in self.diagnostics.get('capture')])
        st, values = self.diagnostics.get('capture')[-1]
        self.assertEqual(st.hardware_id, 'endoscope')
        self.assertGreater(int(values['pairs published']), 0)
        self.assertEqual(values['left size [px]'], '640x360')
        for task in ('left frame rate', 'right frame rate', 'stereo pair rate'):
            self.assertTrue(self.diagnostics.get(task), 'no %s status' % task)

    def check_camera_info(self):
        directory = rospy.get_param('~calibration_dir')
        for e in EYES:
            _, stamps, info = self.infos[e].snapshot()
            self.assertIsNotNone(info, 'no %s camera_info' % e)
            with open(os.path.join(directory, 'endoscope_%s.yaml' % e)) as f:
                calib = yaml.safe_load(f)
            self.assertEqual((info.width, info.height), (calib['image_width'], calib['image_height']))
            self.assertEqual(info.distortion_model, calib['distortion_model'])
            self.assertEqual(list(info.D), calib['distortion_coefficients']['data'])
            self.assertEqual(list(info.K), calib['camera_matrix']['data'])
            self.assertEqual(list(info.R), calib['rectification_matrix']['data'])
            self.assertEqual(list(info.P), calib['projection_matrix']['data'])
            self.assertEqual(info.header.frame_id, 'endoscope/%s_optical_frame' % e)
            images, infos = set(self.images[e].snapshot()[1]), set(stamps)
            self.assertGreaterEqual(len(images & infos), 0.9 * min(len(images), len(infos)) - 2,
                                    '%s camera_info stamps are not those of the images' % e)

    def check_broken(self):
        def errors():
            return [(st, v) for st, v in self.diagnostics.get('capture') if st.level == DiagnosticStatus.ERROR]
        self.assertTrue(wait_until(lambda: errors(), 60.0), 'no ERROR capture status')
        st, values = errors()[-1]
        self.assertIn('left camera not open', st.message)
        self.assertIn('nosuchelement_saras', values['left last error'])
        self.assertEqual(st.hardware_id, 'endoscope')
        first_failures = int(values['left open failures'])
        time.sleep(DURATION)  # the node stays up and keeps retrying
        self.assertTrue(wait_until(lambda: int(errors()[-1][1]['left open failures']) > first_failures, 30.0),
                        'no reopen attempt after %d' % first_failures)
        self.assertTrue(wait_until(lambda: int(errors()[-1][1]['right unmatched (dropped)']) > 10, 30.0),
                        'right frames not counted as unmatched: %s' % errors()[-1][1])
        self.assertTrue(int(errors()[-1][1]['right frames']) > 10)
        self.assertEqual(int(errors()[-1][1]['pairs published']), 0)
        for e in EYES:
            self.assertEqual(self.images[e].snapshot()[0], [], '%s image published without a pair' % e)


if __name__ == '__main__':
    rospy.init_node('stereo_capture_test')
    rostest.rosrun('saras_drivers', 'stereo_capture_test', StereoCaptureTest, sys.argv)
