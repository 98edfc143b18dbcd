#!/usr/bin/env python3
"""rostest checker: jpeg_to_raw turns each JPEG of /visual_feedback/left/image/compressed into a
bgr8 /visual_feedback/left/image with the same header stamp and the decoded pixels."""
import threading
import unittest

import cv2
import numpy as np
import rospy
import rostest
from sensor_msgs.msg import CompressedImage, Image

FRAMES = 10


class CheckDecoder(unittest.TestCase):
    def test_frames_are_decoded(self):
        jpegs, raws = {}, []
        done = threading.Event()

        def jpeg(msg):
            jpegs[msg.header.stamp.to_nsec()] = msg.data

        def raw(msg):
            raws.append(msg)
            if len(raws) >= FRAMES:
                done.set()

        rospy.Subscriber('/visual_feedback/left/image/compressed', CompressedImage, jpeg, queue_size=50)
        rospy.Subscriber('/visual_feedback/left/image', Image, raw, queue_size=50)
        self.assertTrue(done.wait(60.0), 'only %d decoded frames' % len(raws))
        matched = 0
        for msg in raws:
            self.assertEqual((msg.width, msg.height, msg.encoding, msg.step), (320, 180, 'bgr8', 960))
            src = jpegs.get(msg.header.stamp.to_nsec())
            if src is not None:
                expected = cv2.imdecode(np.frombuffer(src, np.uint8), cv2.IMREAD_COLOR)
                self.assertEqual(bytes(msg.data), expected.tobytes())
                matched += 1
        self.assertGreater(matched, FRAMES // 2)


if __name__ == '__main__':
    rospy.init_node('check_decoder')
    rostest.rosrun('saras_operator_view', 'check_decoder', CheckDecoder)
