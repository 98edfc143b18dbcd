#!/usr/bin/env python3
"""CPU cost of the operator view node: idle (no browser) and streaming the augmented stereo to one
headless Chromium page. Needs a running master (roscore); starts its own 30 Hz 640x360 JPEG
stereo publisher and the node on a free port.

  rosrun saras_operator_view stream_cost.py [--seconds 10]
Prints the node's CPU (% of one core) in both states and the frames per second the page received.
"""
import argparse
import os
import subprocess
import threading
import time

import cv2
import numpy as np
import rospy
from sensor_msgs.msg import CompressedImage

from saras_operator_view.browser import PAGE_STATE, HeadlessChromium


def publish(stop):
    pubs = {e: rospy.Publisher('/visual_feedback/%s/image/compressed' % e, CompressedImage, queue_size=2)
            for e in ('left', 'right')}
    base = cv2.GaussianBlur(np.random.default_rng(0).integers(0, 255, (360, 640, 3), dtype=np.uint8), (15, 15), 0)
    frames = [cv2.imencode('.jpg', np.roll(base, 7 * i, axis=1), [cv2.IMWRITE_JPEG_QUALITY, 90])[1].tobytes()
              for i in range(30)]
    rate, i = rospy.Rate(30), 0
    while not stop.is_set() and not rospy.is_shutdown():
        for p in pubs.values():
            m = CompressedImage(format='jpeg', data=frames[i % 30])
            m.header.stamp = rospy.Time.now()
            p.publish(m)
        i += 1
        rate.sleep()
    return len(frames[0])


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def measure(pid, seconds):
    c0, t0 = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    return 100.0 * (cpu_seconds(pid) - c0) / (time.monotonic() - t0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--seconds', type=float, default=10.0)
    args = parser.parse_args(rospy.myargv()[1:])
    rospy.init_node('stream_cost', disable_signals=True)
    stop = threading.Event()
    threading.Thread(target=publish, args=(stop,), daemon=True).start()
    node = subprocess.Popen(['rosrun', 'saras_operator_view', 'operator_view', '_port:=0',
                             '__name:=stream_cost_view'])
    try:
        url = None
        while url is None:
            time.sleep(0.5)
            url = rospy.get_param('/stream_cost_view/url', None)
        pid = node.pid      # rosrun execs the node
        print('idle (no browser): %.1f %% of a core' % measure(pid, args.seconds))
        with HeadlessChromium(url) as browser:
            browser.wait_for("document.getElementById('eye-left').naturalWidth > 0", 60)
            s0, t0 = browser.evaluate(PAGE_STATE), time.monotonic()
            busy = measure(pid, args.seconds)
            s1, t1 = browser.evaluate(PAGE_STATE), time.monotonic()
        fps = (s1['frames_left'] - s0['frames_left']) / (t1 - t0)
        print('one page, 2 x 640x360 JPEG at 30 Hz: %.1f %% of a core, %.1f frames/s per eye' % (busy, fps))
    finally:
        stop.set()
        node.terminate()
        node.wait(10)


if __name__ == '__main__':
    main()
