"""One endoscope frame of a recording with the vision contact estimate drawn on it (demo report).

Drawn offline from the bag, so it costs nothing while recording: the ContactEstimator's
``/mesa_<side>/contact_estimate`` carries, per stereo pair, the image stamp, the state, the depth and
the fitted surface point and outward normal in the left camera's optical frame (README of
saras_visual_feedback); the recorded left image (``/endoscope/left/image_raw/compressed``) with the
same stamp and its ``camera_info`` (K, plumb_bob D) place them in the raw image. Per tool in contact:
the surface patch (circle of the estimator's ``patch_radius`` in the fitted tangent plane, yellow),
the normal (arrow, cyan), the tip (surface point + signed distance x normal, red) and its depth.

:func:`draw_contact` (numpy + OpenCV, no ROS) is the drawing core; :func:`pick_stamp` chooses the
frame: the image stamp at which the most tools are in contact, most confidently.
"""
import math

import cv2
import numpy as np

ESTIMATE_LEN = 15           # estimate layout with the surface point and normal (indices 9-14)
CONTACT = 2                 # state code of a contact
PATCH_RADIUS = 0.012        # [m] ContactEstimator default patch_radius
NORMAL_LENGTH = 0.008       # [m] drawn normal
COLOURS = {'patch': (0, 220, 255), 'normal': (255, 255, 0), 'tip': (0, 0, 255), 'text': (255, 255, 255)}


def _basis(n):
    """Two unit vectors orthogonal to the unit vector n (and to each other)."""
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def project(points, K, D):
    """Raw-image pixels (N, 2) of optical-frame points (N, 3) [m]; NaN rows behind the camera."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    px, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), np.asarray(K, dtype=float).reshape(3, 3),
                              np.asarray(D, dtype=float).ravel())
    px = px.reshape(-1, 2)
    px[pts[:, 2] <= 1e-6] = np.nan
    return px


def draw_contact(image, K, D, surface, normal, signed_distance, label='', patch_radius=PATCH_RADIUS):
    """Draw one estimate on ``image`` (BGR, modified in place): patch outline, normal arrow, tip, label.

    surface (3,) [m] and normal (3,) (unit, outward) in the optical frame of the image's camera.
    Returns the number of drawn elements (0 when the patch is behind the camera or not finite)."""
    s, n = np.asarray(surface, dtype=float), np.asarray(normal, dtype=float)
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(n)) and math.isfinite(signed_distance)) or \
            np.linalg.norm(n) < 1e-9:
        return 0
    n = n / np.linalg.norm(n)
    u, v = _basis(n)
    th = np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)
    ring = s + patch_radius * (np.cos(th)[:, None] * u + np.sin(th)[:, None] * v)
    pts = project(np.vstack([ring, [s, s + NORMAL_LENGTH * n, s + signed_distance * n]]), K, D)
    if not np.all(np.isfinite(pts)):
        return 0
    p = np.round(pts).astype(np.int32)
    cv2.polylines(image, [p[:48].reshape(-1, 1, 2)], True, COLOURS['patch'], 2, cv2.LINE_AA)
    cv2.arrowedLine(image, tuple(int(c) for c in p[48]), tuple(int(c) for c in p[49]), COLOURS['normal'], 2,
                    cv2.LINE_AA, tipLength=0.3)
    cv2.circle(image, tuple(int(c) for c in p[50]), 4, COLOURS['tip'], -1, cv2.LINE_AA)
    if label:
        org = (int(p[:48, 0].max()) + 4, int(p[:48, 1].min()) + 12)
        cv2.putText(image, label, org, cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(image, label, org, cv2.FONT_HERSHEY_SIMPLEX, 0.45, COLOURS['text'], 1, cv2.LINE_AA)
    return 3


def pick_stamp(estimates):
    """estimates: {side: [data tuples]}; the image stamp [s] with the most tools in contact (ties: the
    highest smallest confidence), or None when no estimate in contact carries a surface point."""
    by_stamp = {}
    for side, rows in estimates.items():
        for d in rows:
            if len(d) >= ESTIMATE_LEN and int(d[1]) == CONTACT and all(math.isfinite(x) for x in d[9:15]):
                by_stamp.setdefault(d[0], {})[side] = d
    if not by_stamp:
        return None
    return max(by_stamp, key=lambda st: (len(by_stamp[st]), min(d[4] for d in by_stamp[st].values())))


def write_contact_frame(bag_path, out_png, sides=('left', 'right'), patch_radius=PATCH_RADIUS,
                        image_topic='/endoscope/left/image_raw/compressed', info_topic='/endoscope/left/camera_info'):
    """Draw the chosen frame of a recording into ``out_png``; returns a caption, or None (no contact
    estimate with a surface, or its image/camera_info not recorded)."""
    import rosbag
    with rosbag.Bag(bag_path) as bag:
        estimates = {s: [tuple(m.data) for _, m, _ in bag.read_messages(['/mesa_%s/contact_estimate' % s])]
                     for s in sides}
        stamp = pick_stamp(estimates)
        if stamp is None:
            return None
        info = next((m for _, m, _ in bag.read_messages([info_topic])), None)
        image = None
        for _, m, _ in bag.read_messages([image_topic]):
            if abs(m.header.stamp.to_sec() - stamp) < 1e-6:
                image = cv2.imdecode(np.frombuffer(m.data, np.uint8), cv2.IMREAD_COLOR)
                break
        t0 = bag.get_start_time()
    if image is None or info is None:
        return None
    drawn = []
    for side in sides:
        d = next((d for d in estimates[side] if d[0] == stamp and len(d) >= ESTIMATE_LEN), None)
        if d is None or int(d[1]) != CONTACT:
            continue
        label = '%s %.1f mm' % (side, 1e3 * d[2])
        if draw_contact(image, info.K, info.D, d[9:12], d[12:15], d[3], label, patch_radius):
            drawn.append('%s: depth %.1f mm, confidence %.2f' % (side, 1e3 * d[2], d[4]))
    cv2.imwrite(out_png, image)
    return 'left endoscope image at t = %.2f s (%s); yellow: fitted surface patch (radius %.0f mm), cyan: its ' \
           'outward normal, red: the tool tip' % (stamp - t0, '; '.join(drawn), 1e3 * patch_radius)
