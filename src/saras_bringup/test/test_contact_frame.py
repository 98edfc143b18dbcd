"""saras_bringup.contact_frame: the contact estimate drawn on a recorded endoscope frame (report)."""
import math

import numpy as np
import pytest

cv2 = pytest.importorskip('cv2')
from saras_bringup.contact_frame import ESTIMATE_LEN, draw_contact, pick_stamp, project  # noqa: E402

K = [450.0, 0.0, 319.5, 0.0, 450.0, 179.5, 0.0, 0.0, 1.0]
D = [0.0] * 5


def estimate(stamp, state, depth, confidence, surface=(0.0, 0.0, 0.1), normal=(0.0, 0.0, -1.0)):
    return (stamp, state, depth, -depth, confidence, 0.0, 0.0, 1.0, 0.0) + tuple(surface) + tuple(normal) + \
        (300.0, 160.0, 40.0, 40.0)


def test_patch_normal_and_tip_land_where_the_geometry_says():
    img = np.zeros((360, 640, 3), np.uint8)
    # surface 10 cm ahead on the optical axis, normal tilted towards the camera and +x, tip 3 mm deep
    n = np.array([0.3, 0.0, -1.0]) / math.hypot(0.3, 1.0)
    assert draw_contact(img, K, D, (0.0, 0.0, 0.1), n, -0.003, 'left 3.0 mm', patch_radius=0.012) == 3
    yellow = np.all(img == (0, 220, 255), axis=2)
    ys, xs = np.nonzero(yellow)
    # patch radius 12 mm at 10 cm: ~54 px around the centre pixel (tilt shrinks x a little)
    assert 40 < xs.max() - 319.5 < 60 and 45 < 179.5 - ys.min() < 60
    tip_px = project([np.array([0.0, 0.0, 0.1]) - 0.003 * n], K, D)[0]
    assert tuple(img[int(round(tip_px[1])), int(round(tip_px[0]))]) == (0, 0, 255)
    cyan = np.nonzero(np.all(img == (255, 255, 0), axis=2))[1]
    assert cyan.size and cyan.max() > 319.5 + 5          # the arrow leans towards +x with the normal


def test_nothing_drawn_for_unknown_or_behind_the_camera():
    img = np.zeros((36, 64, 3), np.uint8)
    assert draw_contact(img, K, D, (float('nan'),) * 3, (0, 0, -1), 0.0) == 0
    assert draw_contact(img, K, D, (0.0, 0.0, -0.1), (0, 0, -1), 0.0) == 0
    assert not img.any()


def test_pick_stamp_prefers_both_tools_in_contact_then_confidence():
    assert len(estimate(1.0, 2, 0.003, 0.9)) >= ESTIMATE_LEN
    est = {'left': [estimate(1.0, 2, 0.003, 0.9), estimate(2.0, 2, 0.002, 0.5), estimate(3.0, 2, 0.002, 0.8)],
           'right': [estimate(1.0, 1, 0.0, 0.9), estimate(2.0, 2, 0.004, 0.6), estimate(3.0, 2, 0.004, 0.7)]}
    assert pick_stamp(est) == 3.0
    unknown = estimate(4.0, 0, float('nan'), 0.0, (float('nan'),) * 3, (float('nan'),) * 3)
    assert pick_stamp({'left': [unknown], 'right': [estimate(5.0, 1, 0.0, 1.0)]}) is None
    assert pick_stamp({'left': [(1.0, 2, 0.003, -0.003, 0.9, 0, 0, 1, 0)]}) is None   # old layout: no surface


def test_report_step_on_a_small_synthetic_bag(tmp_path):
    rosbag = pytest.importorskip('rosbag')
    import rospy
    from sensor_msgs.msg import CameraInfo, CompressedImage
    from std_msgs.msg import Float64MultiArray
    from saras_bringup.contact_frame import write_contact_frame
    bag_path = str(tmp_path / 'small.bag')
    img = np.full((360, 640, 3), 90, np.uint8)
    with rosbag.Bag(bag_path, 'w') as bag:
        for i, st in enumerate((100.0, 100.033)):
            stamp = rospy.Time.from_sec(st)
            info = CameraInfo(width=640, height=360, K=K, D=D, distortion_model='plumb_bob')
            info.header.stamp = stamp
            c = CompressedImage(format='jpeg', data=cv2.imencode('.jpg', img)[1].tobytes())
            c.header.stamp = stamp
            bag.write('/endoscope/left/camera_info', info, stamp)
            bag.write('/endoscope/left/image_raw/compressed', c, stamp)
            bag.write('/mesa_left/contact_estimate', Float64MultiArray(data=estimate(st, 2, 0.003, 0.5 + i * 0.3)),
                      stamp)
    out = str(tmp_path / 'frame.png')
    caption = write_contact_frame(bag_path, out, sides=('left', 'right'))
    assert caption and 'left: depth 3.0 mm, confidence 0.80' in caption and 't = 0.03 s' in caption
    drawn = cv2.imread(out)
    assert drawn.shape == (360, 640, 3) and np.any(np.all(drawn == (0, 220, 255), axis=2))
    empty = str(tmp_path / 'empty.bag')
    with rosbag.Bag(empty, 'w') as bag:
        bag.write('/mesa_left/contact_estimate', Float64MultiArray(data=estimate(1.0, 1, 0.0, 1.0)), rospy.Time(1))
    assert write_contact_frame(empty, str(tmp_path / 'none.png')) is None


def test_report_agreement_table_compares_known_estimates_with_the_nearest_truth():
    pytest.importorskip('matplotlib')
    import collections
    from saras_bringup.report import contact_agreement, contact_agreement_html
    Truth = collections.namedtuple('Truth', 'depth')
    Est = collections.namedtuple('Est', 'data')
    truth = [(10.0 + 0.1 * i, Truth(0.003 if i >= 5 else 0.0)) for i in range(10)]
    est = [(10.0 + 0.1 * i + 0.05, Est(estimate(10.0 + 0.1 * i, 2 if i >= 5 else 1, 0.0035 if i >= 5 else 0.0, 0.8)))
           for i in range(8)]
    est.append((11.0, Est(estimate(10.8, 0, float('nan'), 0.0))))
    rows = contact_agreement({'/mesa_left/contact_truth': truth, '/mesa_left/contact_estimate': est})
    r = rows['left']
    assert r['estimates'] == 9 and r['unknown'] == pytest.approx(1 / 9.0)
    assert r['truth_contact'] == 4 and r['known_in_contact'] == 3          # t = 10.5 .. 10.8; 10.8 unknown
    assert r['rms_mm'] == pytest.approx(math.sqrt(3 * 0.5 ** 2 / 8.0)) and r['max_true_mm'] == pytest.approx(3.0)
    assert r['rms_contact_mm'] == pytest.approx(0.5)                       # t = 10.5 .. 10.7, 0.5 mm deeper
    assert r['latency_ms'][0] == pytest.approx(50.0) and r['latency_ms'][1] < 250.0
    assert 'left' in contact_agreement_html(rows) and 'right' not in rows


def test_report_agreement_uses_the_truth_at_the_pose_stamps():
    # a dip at 5 mm/s: truth recorded 80 ms after its pose stamp; the estimate exact at its image stamp
    pytest.importorskip('matplotlib')
    import collections
    from saras_bringup.report import contact_agreement
    Truth = collections.namedtuple('Truth', 'depth')
    Arr = collections.namedtuple('Arr', 'data')

    def depth(t):
        return max(0.0, 0.005 * (t - 10.0))
    stamps = [10.0 + i / 30.0 for i in range(30)]
    tip = [(t + 0.08, Arr([0.0, 0.0, 0.0, -depth(t), t])) for t in stamps]
    truth = [(t + 0.08, Truth(depth(t))) for t in stamps]
    est = [(t + 0.1, Arr(estimate(t, 2, depth(t), 0.9))) for t in stamps[3:-3]]
    late = contact_agreement({'/mesa_left/contact_truth': truth, '/mesa_left/contact_estimate': est})['left']
    assert late['rms_contact_mm'] > 0.3                                   # 80 ms x 5 mm/s = 0.4 mm
    rows = contact_agreement({'/mesa_left/contact_truth': truth, '/mesa_left/contact_truth_tip': tip,
                              '/mesa_left/contact_estimate': est})
    assert rows['left']['rms_contact_mm'] == pytest.approx(0.0, abs=1e-6)
