#!/usr/bin/env python3
"""rostest checker: headless Chromium shows the operator view live (both eyes decoded, frame
counters rising, distances changing with their colours, energies, health) and the node subscribes
to the images only while the page is open."""
import os
import time
import unittest

import rosgraph
import rospkg
import rospy
import rostest

from saras_operator_view.browser import PAGE_STATE, HeadlessChromium

IMAGE_TOPIC = '/visual_feedback/left/image/compressed'
TIMEOUT = 90.0


def image_subscribers():
    _, subs, _ = rosgraph.Master('/check_browser').getSystemState()
    return [n for topic, nodes in subs if topic == IMAGE_TOPIC for n in nodes]


def wait_until(predicate, timeout):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.2)
    return predicate()


def screenshot_path():
    out = os.path.join(rospkg.get_test_results_dir(), 'saras_operator_view')
    os.makedirs(out, exist_ok=True)
    return os.path.join(out, 'operator_view_page.png')


class CheckBrowser(unittest.TestCase):
    def test_page_is_live(self):
        url = None
        deadline = time.monotonic() + TIMEOUT
        while url is None and time.monotonic() < deadline:
            url = rospy.get_param('/operator_view/url', None)
            time.sleep(0.2)
        self.assertIsNotNone(url, 'operator_view did not publish ~url')
        self.assertTrue(url.startswith('http://127.0.0.1:'), url)
        self.assertEqual(image_subscribers(), [], 'images subscribed before any browser')

        with HeadlessChromium(url, timeout=TIMEOUT) as browser:
            live = browser.wait_for("(() => { const s = %s; return s.width_left > 0 && s.width_right > 0 && "
                                    "s.frames_left > 0 && s.frames_right > 0 && s.link === 'live' && "
                                    "s.distances.length === 4 && s.health.length === 2; })()" % PAGE_STATE, TIMEOUT)
            first = browser.evaluate(PAGE_STATE)
            self.assertTrue(live, 'page not live within %.0f s: %s' % (TIMEOUT, first))
            self.assertIn('/operator_view', image_subscribers())
            self.assertTrue(wait_until(lambda: browser.evaluate(PAGE_STATE)['distances'][0] != first['distances'][0]
                                       and browser.evaluate(PAGE_STATE)['frames_left'] > first['frames_left'] + 5,
                                       TIMEOUT), 'distances/frames did not change')
            regions = set()
            wait_until(lambda: regions.update([browser.evaluate(PAGE_STATE)['regions'][0]]) or
                       {'collision', 'warning', 'safe'} <= regions, TIMEOUT)
            second = browser.evaluate(PAGE_STATE)
            browser.screenshot(screenshot_path())
        rospy.loginfo('operator view: first %s, second %s, regions seen %s', first, second, regions)
        self.assertEqual(first['width_left'], 320)
        self.assertEqual(regions, {'collision', 'warning', 'safe'})
        self.assertEqual(second['regions'][2:], ['safe', 'unknown'])          # 50 mm, NaN
        self.assertIn('no data', second['distances'][3])
        self.assertTrue(all(' J' in t for t in second['tanks']), second['tanks'])
        self.assertTrue(any('WARN' in h and 'Teleoperation' in h for h in second['health']), second['health'])
        self.assertGreater(os.path.getsize(screenshot_path()), 10000)
        self.assertEqual(rospy.get_param('/operator_view/url'), url)
        self.assertTrue(wait_until(lambda: image_subscribers() == [], TIMEOUT),
                        'images still subscribed after the browser closed: %s' % image_subscribers())


if __name__ == '__main__':
    rospy.init_node('check_browser')
    rostest.rosrun('saras_operator_view', 'check_browser', CheckBrowser)
