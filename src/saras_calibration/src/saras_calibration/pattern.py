"""The circular calibration pattern (D7.2 Section 4.3, Figure 10).

Geometry (defaults, all configurable): ``n_dots`` black dots of 5 mm diameter evenly spaced on a
circle of radius 100 mm (touched by the arms), and four 25 mm ArUco markers (DICT_4X4_50,
ids 0-3) centred on a concentric circle of radius 60 mm at 45, 135, 225 and 315 deg (seen
by the endoscope).

Pattern frame (OpenCV planar-target convention, identical to the board frame of
``saras_simulation``' endoscope simulator): origin at the circle centre on the printed surface,
x towards dot 0, y towards dot ``n_dots/4``, z *into* the board (a camera looking at the printed
side looks along +z; printed images are read with x to the right and y downwards). Dot ``k`` is at
angle ``360 k / n_dots`` deg from x towards y. Marker edges are aligned with the pattern axes;
ArUco corner order (top-left, top-right, bottom-right, bottom-left of the marker image) is
``(-h, -h), (h, -h), (h, h), (-h, h)`` around the marker centre, ``h`` = half the side.
Lying printed side up on the table, the pattern frame is the world frame rotated by pi about x.
"""
from dataclasses import dataclass

import cv2
import numpy as np

from .registration import register_points
from saras_common.transforms import inverse, make_transform, validate_transform

__all__ = ['CircularPattern', 'PatternDetectionError']


class PatternDetectionError(RuntimeError):
    """The pattern could not be located in an image (too few markers, bad calibration...)."""


@dataclass
class CircularPattern:
    """Geometry of the printed pattern. Lengths in metres, angles in degrees."""
    dot_circle_radius: float = 0.100
    dot_diameter: float = 0.005
    n_dots: int = 8
    marker_circle_radius: float = 0.060
    marker_size: float = 0.025
    marker_ids: tuple = (0, 1, 2, 3)
    marker_angles_deg: tuple = (45.0, 135.0, 225.0, 315.0)
    aruco_dictionary: str = 'DICT_4X4_50'

    def __post_init__(self):
        checks = [('dot_circle_radius', self.dot_circle_radius > 0), ('dot_diameter', self.dot_diameter > 0),
                  ('n_dots', int(self.n_dots) >= 3), ('marker_size', self.marker_size > 0),
                  ('marker_circle_radius', self.marker_circle_radius > 0),
                  ('marker_ids', len(self.marker_ids) == len(self.marker_angles_deg) and len(self.marker_ids) >= 1),
                  ('aruco_dictionary', hasattr(cv2.aruco, str(self.aruco_dictionary)))]
        for name, ok in checks:
            if not ok:
                raise ValueError('invalid pattern parameter %s = %r' % (name, getattr(self, name)))
        self.n_dots = int(self.n_dots)
        self.marker_ids = tuple(int(i) for i in self.marker_ids)

    @classmethod
    def from_dict(cls, d):
        """Build from a parameter dictionary (unknown keys are an error)."""
        d = dict(d or {})
        unknown = set(d) - set(cls.__dataclass_fields__)
        if unknown:
            raise ValueError('unknown pattern parameter(s): %s' % ', '.join(sorted(unknown)))
        return cls(**d)

    def dot_positions(self):
        """(n_dots, 3) dot centres in the pattern frame [m]."""
        a = 2.0 * np.pi * np.arange(self.n_dots) / self.n_dots
        r = self.dot_circle_radius
        return np.column_stack([r * np.cos(a), r * np.sin(a), np.zeros_like(a)])

    def marker_poses(self):
        """Dict id -> 4x4 ``T_pattern_marker`` (marker centre, axes aligned with the pattern)."""
        out = {}
        for mid, ang in zip(self.marker_ids, self.marker_angles_deg):
            a = np.radians(ang)
            out[mid] = make_transform(None, [self.marker_circle_radius * np.cos(a),
                                             self.marker_circle_radius * np.sin(a), 0.0])
        return out

    def marker_corners(self, marker_id):
        """(4, 3) corners of a marker in the pattern frame, ArUco order (TL, TR, BR, BL)."""
        return self._marker_local() + self.marker_poses()[marker_id][:3, 3]

    def _marker_local(self):
        h = self.marker_size / 2.0
        return np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])

    def dictionary(self):
        return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.aruco_dictionary))

    # ---- endoscope side -------------------------------------------------------------------
    def pose_from_marker_poses(self, marker_poses):
        """``T_cam_pattern`` from individual marker poses (e.g. an external ArUco detector).

        :param marker_poses: dict id -> 4x4 ``T_cam_marker`` [m]; unknown ids are ignored.
        :returns: (4x4 ``T_cam_pattern``, rms corner residual [m], used ids).
        :raises PatternDetectionError: no known marker.
        """
        cam, pat, used = [], [], []
        local = self._marker_local()
        for mid, T in marker_poses.items():
            if int(mid) not in self.marker_ids:
                continue
            T = validate_transform(T, 'marker %d pose' % mid)
            cam.append(local @ T[:3, :3].T + T[:3, 3])
            pat.append(self.marker_corners(int(mid)))
            used.append(int(mid))
        if not used:
            raise PatternDetectionError('none of the pattern markers %s was given' % (self.marker_ids,))
        T, rms = register_points(np.vstack(cam), np.vstack(pat), min_spread=1e-4)
        return T, rms, sorted(used)

    def detect(self, image, K, D, min_markers=2):
        """Locate the pattern in an image from its ArUco markers (all corners in one PnP).

        :param image: grey or BGR image. :param K: 3x3 camera matrix [px]. :param D: distortion.
        :param min_markers: minimum number of pattern markers that must be detected.
        :returns: (4x4 ``T_cam_pattern``, reprojection rms [px], detected ids).
        :raises PatternDetectionError: fewer than ``min_markers`` markers or PnP failure.
        """
        if image is None or image.size == 0:
            raise PatternDetectionError('empty image')
        grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
        params = cv2.aruco.DetectorParameters_create()
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
        corners, ids, _ = cv2.aruco.detectMarkers(grey, self.dictionary(), parameters=params)
        img_pts, obj_pts, found = [], [], []
        if ids is not None:
            for c, i in zip(corners, ids.ravel()):
                if int(i) in self.marker_ids and int(i) not in found:
                    img_pts.append(c.reshape(4, 2))
                    obj_pts.append(self.marker_corners(int(i)))
                    found.append(int(i))
        if len(found) < min_markers:
            raise PatternDetectionError('only %d of the pattern markers detected (need %d)' % (len(found), min_markers))
        obj = np.vstack(obj_pts).astype(np.float64)
        img = np.vstack(img_pts).astype(np.float64)
        K = np.asarray(K, dtype=float).reshape(3, 3)
        D = np.asarray(D, dtype=float).ravel()
        ok, rvec, tvec = cv2.solvePnP(obj, img, K, D, flags=cv2.SOLVEPNP_SQPNP)
        if not ok:
            raise PatternDetectionError('solvePnP failed')
        rvec, tvec = cv2.solvePnPRefineLM(obj, img, K, D, rvec, tvec)
        proj, _ = cv2.projectPoints(obj, rvec, tvec, K, D)
        rms = float(np.sqrt(np.mean(np.sum((proj.reshape(-1, 2) - img) ** 2, axis=1))))
        T = make_transform(cv2.Rodrigues(rvec)[0], tvec.ravel())
        return T, rms, sorted(found)

    # ---- rendering (tests, simulators) ----------------------------------------------------
    def texture(self, resolution=0.0002):
        """Top view of the printed pattern: (image uint8, metres per pixel, half width [m]).
        Pixel (u, v) is at pattern (x, y) = ((u + 0.5) * res - half, (v + 0.5) * res - half)."""
        half = self.dot_circle_radius + 2.0 * self.dot_diameter
        n = int(np.ceil(2.0 * half / resolution))
        img = np.full((n, n), 255, np.uint8)

        def px(x, y):
            return (int(round((x + half) / resolution - 0.5)), int(round((y + half) / resolution - 0.5)))

        for p in self.dot_positions():
            cv2.circle(img, px(p[0], p[1]), int(round(self.dot_diameter / 2.0 / resolution)), 0, -1, cv2.LINE_AA)
        side = int(round(self.marker_size / resolution))
        for mid in self.marker_ids:
            m = cv2.aruco.drawMarker(self.dictionary(), mid, side)
            c = self.marker_corners(mid)
            u0, v0 = px(c[0, 0], c[0, 1])
            img[v0:v0 + side, u0:u0 + side] = m
        return img, resolution, half

    def render(self, K, size, T_cam_pattern, background=60):
        """Pinhole (undistorted) view of the pattern: uint8 grey image of ``size`` (w, h)."""
        tex, res, half = self.texture()
        # Homography texture pixel -> image pixel through the pattern plane.
        S = np.array([[res, 0.0, -half + 0.5 * res], [0.0, res, -half + 0.5 * res], [0.0, 0.0, 1.0]])
        T = np.asarray(T_cam_pattern, dtype=float)
        H = np.asarray(K, dtype=float) @ np.column_stack([T[:3, 0], T[:3, 1], T[:3, 3]]) @ S
        out = cv2.warpPerspective(tex, H, tuple(size), flags=cv2.INTER_AREA, borderValue=background)
        return out


def pattern_in_base_from_endoscope(T_base_ee, T_ee_cam, T_cam_pattern):
    """``T_base_pattern`` for the ECM: end effector (kinematics) x hand-eye x detection."""
    return T_base_ee @ T_ee_cam @ T_cam_pattern


def base_in_pattern(T_base_pattern):
    """``T_pattern_base`` (the inverse), the form written to the world-frame file."""
    return inverse(T_base_pattern)
