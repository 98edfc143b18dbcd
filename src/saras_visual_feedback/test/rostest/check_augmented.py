#!/usr/bin/env python3
"""rostest checker of the VisualFeedback nodelet (see ../visual_feedback*.test).

~mode:
  nominal    augmented images at the input rate, one output per input, and each tool drawn in its
             region's colour at the pixel OpenCV's cv2.projectPoints predicts (distortion included)
  rate       only the rate part of nominal (used with the real saras_simulation/endoscope_sim)
  reconfigure  dynamic_reconfigure changes thresholds/colours live and refuses invalid requests
  bad_input  malformed images, NaN poses and short distance arrays: the nodelet keeps publishing
             and /diagnostics counts the rejections
  lazy       no camera/pose subscription while nobody listens; subscribes per eye on demand
"""
import math
import re
import sys
import threading
import time
import unittest

import cv2
import numpy as np
import rosgraph
import rospy
import rostest
from diagnostics import DiagnosticsRecorder
from sensor_msgs.msg import CompressedImage, Image

import scene

PKG = 'saras_visual_feedback'
EYES = ('left', 'right')


def image_array(msg):
    return np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)[:, :3 * msg.width].reshape(
        msg.height, msg.width, 3)


def project(eye, p_world):
    """Pixel of a world point in an eye's raw image, by OpenCV (the independent reference)."""
    p_cam = scene.to_frame('endoscope/%s_optical_frame' % eye, p_world)
    k = np.array(scene.K).reshape(3, 3)
    px, _ = cv2.projectPoints(p_cam.reshape(1, 1, 3), np.zeros(3), np.zeros(3), k, np.array(scene.D))
    return px.reshape(2)


def subscribers(topic):
    _, subs, _ = rosgraph.Master('/check_augmented').getSystemState()
    for name, nodes in subs:
        if name == topic:
            return [n for n in nodes if n != rospy.get_name()]
    return []


class Recorder:
    def __init__(self, topic):
        self.lock = threading.Lock()
        self.count = 0
        self.stamps = set()
        self.log = []  # (receipt wall time [s], stamp [ns]) per message
        self.last = None
        self.sub = rospy.Subscriber(topic, Image, self.cb, queue_size=20, buff_size=2 ** 24)

    def cb(self, msg):
        with self.lock:
            self.count += 1
            self.stamps.add(msg.header.stamp.to_nsec())
            self.log.append((time.time(), msg.header.stamp.to_nsec()))
            self.last = msg


def wait_for(predicate, timeout):
    end = time.time() + timeout
    while time.time() < end and not rospy.is_shutdown():
        if predicate():
            return True
        time.sleep(0.05)
    return predicate()


class TestVisualFeedback(unittest.TestCase):
    def setUp(self):
        self.mode = rospy.get_param('~mode', 'nominal')
        self.rate = rospy.get_param('~rate', 30.0)

    def test_scenario(self):
        getattr(self, 'scenario_' + self.mode)()

    def scenario_nominal(self):
        diagnostics = DiagnosticsRecorder('visual_feedback')
        outs = self.check_rate()
        self.check_drawing(outs)
        self.check_colour_census(diagnostics)
        self.check_compressed()

    def check_colour_census(self, diagnostics):
        """/diagnostics counts the frames drawn in each colour: the scene has all three."""
        n = sum(o.count for o in self.last_outs.values())
        self.assertTrue(wait_for(lambda: diagnostics.statuses, 5.0), 'no visual_feedback status on /diagnostics')
        values = DiagnosticsRecorder.values(diagnostics.statuses[-1])
        red, yellow, green = (int(values['frames with a %s tool' % c]) for c in ('red', 'yellow', 'green'))
        # Every output frame has each colour once (both eyes): at least the frames seen so far.
        rospy.loginfo('colour census: red %d, yellow %d, green %d (%d frames received)', red, yellow, green, n)
        for colour, count in (('red', red), ('yellow', yellow), ('green', green)):
            self.assertGreater(count, 0.5 * n, '%s drawn in %d frames only (%d received)' % (colour, count, n))

    def check_compressed(self):
        """<eye>/image/compressed: JPEG of the augmented image, produced on demand."""
        got = []
        sub = rospy.Subscriber('/visual_feedback/left/image/compressed', CompressedImage, got.append, queue_size=5)
        self.assertTrue(wait_for(lambda: len(got) > 3, 10.0), 'no compressed augmented image')
        sub.unregister()
        msg = got[-1]
        self.assertEqual(msg.format, 'bgr8; jpeg compressed bgr8')
        img = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_COLOR)
        self.assertEqual(img.shape, (scene.HEIGHT, scene.WIDTH, 3))
        px = project('left', scene.TOOLS['mesa_left'][2])
        b, g, r = img[int(round(px[1])), int(round(px[0]))].astype(int)
        self.assertTrue(r > 200 and g < 80 and b < 80, 'left tool tip not red in the JPEG: %s' % ((r, g, b),))

    def scenario_rate(self):
        """Output at the input rate (any image source, e.g. the real endoscope_sim)."""
        self.check_rate()

    def check_rate(self):
        outs = {e: Recorder('/visual_feedback/%s/image' % e) for e in EYES}
        self.assertTrue(wait_for(lambda: all(o.count > 5 for o in outs.values()), 20.0), 'no augmented images')
        ins = {e: Recorder('/endoscope/%s/image_raw' % e) for e in EYES}
        self.assertTrue(wait_for(lambda: all(i.count > 2 for i in ins.values()), 5.0))
        t0 = time.time()
        time.sleep(6.0)
        t1 = time.time()
        elapsed = t1 - t0
        for e in EYES:
            with ins[e].lock:
                window = [stamp for (t, stamp) in ins[e].log if t0 <= t < t1]
            n_in = len(window)
            self.assertGreaterEqual(n_in / elapsed, 0.8 * self.rate, 'simulated endoscope too slow')
            # Output at the input rate: every input frame of the window comes out, with its stamp
            # (frames still queued in the nodelet or in our subscriber are waited for), once.
            def all_out(rec=outs[e], frames=set(window)):
                with rec.lock:
                    return frames <= rec.stamps
            wait_for(all_out, 5.0)
            with outs[e].lock:
                missing = set(window) - outs[e].stamps
                out_stamps = [stamp for (_, stamp) in outs[e].log]
            rospy.loginfo('%s: %d in in %.1f s, %d of them not out', e, n_in, elapsed, len(missing))
            self.assertLessEqual(len(missing), 2, '%s: %d of %d input frames not out' % (e, len(missing), n_in))
            self.assertEqual(len(out_stamps), len(set(out_stamps)), '%s: a frame came out twice' % e)
        self.last_outs = outs
        return outs

    def check_drawing(self, outs):
        for e in EYES:
            msg = outs[e].last
            self.assertEqual(msg.encoding, 'bgr8')
            self.assertEqual(msg.header.frame_id, 'endoscope/%s_optical_frame' % e)
            img = image_array(msg)
            for name, (_, _, tip, distance, _) in scene.TOOLS.items():
                px = project(e, tip)
                u, v = int(round(px[0])), int(round(px[1]))
                r, g, b = scene.EXPECTED_RGB[name]
                expected = np.array([b, g, r], dtype=np.uint8)
                self.assertTrue(np.array_equal(img[v, u], expected),
                                '%s eye, %s (d=%.3f m): pixel (%d, %d) is %s, expected BGR %s' % (
                                    e, name, distance, u, v, img[v, u], expected))
                # The filled tip circle (radius 6 px) is centred on OpenCV's pixel (+-1 px): the
                # pixels 4 px away in the four directions are inside it (the shaft cannot fake
                # more than one of them).
                for du, dv in ((4, 0), (-4, 0), (0, 4), (0, -4)):
                    q = (int(round(px[0] + du)), int(round(px[1] + dv)))
                    self.assertTrue(np.array_equal(img[q[1], q[0]], expected),
                                    '%s %s: pixel %s of the tip circle is %s' % (e, name, q, img[q[1], q[0]]))
            # The left tool's shaft: 2 cm up the shaft towards its trocar, in its colour.
            tip = np.array(scene.TOOLS['mesa_left'][2])
            rcm = np.array(scene.FRAMES['mesa_left/rcm'][1])
            p = tip + 0.02 * (rcm - tip) / np.linalg.norm(rcm - tip)
            px = project(e, p)
            self.assertTrue(np.array_equal(img[int(round(px[1])), int(round(px[0]))], np.array([0, 0, 255], np.uint8)),
                            'shaft of mesa_left not drawn red at %s' % px)

    def scenario_reconfigure(self):
        """dynamic_reconfigure changes the thresholds and colours live; invalid requests are refused."""
        from dynamic_reconfigure.client import Client
        outs = {e: Recorder('/visual_feedback/%s/image' % e) for e in EYES}
        self.assertTrue(wait_for(lambda: all(o.count > 5 for o in outs.values()), 20.0), 'no augmented images')
        client = Client('/visual_feedback', timeout=10.0)

        def colour_at(tool, eye='left'):
            n = outs[eye].count
            self.assertTrue(wait_for(lambda: outs[eye].count > n + 3, 5.0))  # frames drawn after the change
            img = image_array(outs[eye].last)
            px = project(eye, scene.TOOLS[tool][2])
            b, g, r = img[int(round(px[1])), int(round(px[0]))]
            return int(r), int(g), int(b)

        time.sleep(1.5)  # first distances and poses in (lazily subscribed with the first viewer)
        self.assertEqual(colour_at('mesa_right'), (255, 255, 0))  # 0.012 m: warning by default
        cfg = client.update_configuration({'collision_threshold': 0.015, 'warning_threshold': 0.06})
        self.assertAlmostEqual(cfg['collision_threshold'], 0.015)
        self.assertEqual(colour_at('mesa_right'), (255, 0, 0))   # now a collision
        self.assertEqual(colour_at('PSM1'), (255, 255, 0))       # 0.05 m: now a warning
        # Invalid: warning below collision -> refused, the values in use are reported back.
        cfg = client.update_configuration({'warning_threshold': 0.001})
        self.assertAlmostEqual(cfg['warning_threshold'], 0.06)
        self.assertEqual(colour_at('PSM1'), (255, 255, 0))
        cfg = client.update_configuration({'collision_colour': 'not a colour'})
        self.assertEqual(cfg['collision_colour'], '#ff0000')
        client.update_configuration({'collision_colour': '#ff00ff'})
        self.assertEqual(colour_at('mesa_right'), (255, 0, 255))

    def scenario_bad_input(self):
        diagnostics = DiagnosticsRecorder('visual_feedback')
        outs = {e: Recorder('/visual_feedback/%s/image' % e) for e in EYES}
        self.assertTrue(wait_for(lambda: all(o.count > 5 for o in outs.values()), 20.0), 'no augmented images')
        ins = {e: Recorder('/endoscope/%s/image_raw' % e) for e in EYES}
        self.assertTrue(wait_for(lambda: all(i.count > 2 for i in ins.values()), 5.0))
        start = {e: (ins[e].count, outs[e].count) for e in EYES}
        time.sleep(5.0)
        for e in EYES:
            n_in = ins[e].count - start[e][0]
            n_out = outs[e].count - start[e][1]
            rospy.loginfo('%s: %d in, %d out', e, n_in, n_out)
            # One image in five is truncated and rejected; the others come out.
            self.assertGreater(n_out, 0.7 * n_in)
            self.assertLess(n_out, 0.9 * n_in + 2)
        self.assertTrue(diagnostics.statuses, 'no visual_feedback status on /diagnostics')
        values = DiagnosticsRecorder.values(diagnostics.statuses[-1])
        rejected = sum(int(values[k]) for k in ('left rejected images', 'right rejected images',
                                                'rejected poses', 'rejected distance arrays'))
        received = int(values['left frames in']) + int(values['right frames in'])
        self.assertGreater(rejected, 10)
        self.assertGreater(received, rejected)
        # Still alive and drawing after all that.
        n = outs['left'].count
        self.assertTrue(wait_for(lambda: outs['left'].count > n + 10, 5.0))

    def scenario_lazy(self):
        time.sleep(3.0)  # the simulated endoscope is running, nobody watches the HMD topics
        for e in EYES:
            self.assertEqual(subscribers('/endoscope/%s/image_raw' % e), [], 'subscribed without outputs')
        self.assertEqual(subscribers('/mesa_left/ee_pose'), [])
        left = Recorder('/visual_feedback/left/image')
        self.assertTrue(wait_for(lambda: left.count > 5, 10.0), 'no left image after subscribing')
        self.assertNotEqual(subscribers('/endoscope/left/image_raw'), [])
        self.assertEqual(subscribers('/endoscope/right/image_raw'), [], 'right camera subscribed for a left viewer')
        self.assertNotEqual(subscribers('/mesa_left/ee_pose'), [])
        left.sub.unregister()
        self.assertTrue(wait_for(lambda: subscribers('/endoscope/left/image_raw') == [], 5.0),
                        'still subscribed to the camera after the last viewer left')
        self.assertTrue(wait_for(lambda: subscribers('/mesa_left/ee_pose') == [], 5.0))
        # A viewer of the JPEG stream alone also wakes its camera up.
        got = []
        sub = rospy.Subscriber('/visual_feedback/right/image/compressed', CompressedImage, got.append, queue_size=2)
        self.assertTrue(wait_for(lambda: len(got) > 3, 10.0), 'no compressed right image')
        self.assertNotEqual(subscribers('/endoscope/right/image_raw'), [])
        self.assertEqual(subscribers('/endoscope/left/image_raw'), [])
        sub.unregister()
        self.assertTrue(wait_for(lambda: subscribers('/endoscope/right/image_raw') == [], 5.0))


if __name__ == '__main__':
    rospy.init_node('check_augmented')
    rostest.rosrun(PKG, 'check_augmented_' + rospy.get_param('~mode', 'nominal'), TestVisualFeedback, sys.argv)
