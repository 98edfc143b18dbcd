"""Stereo endoscope simulator core (Decklink stand-in), ROS-agnostic.

* :class:`CameraModel`: pinhole + plumb_bob/rational_polynomial distortion read from a
  camera_info YAML as written by ``camera_calibration`` (image_width, image_height,
  camera_matrix, distortion_model, distortion_coefficients, rectification_matrix,
  projection_matrix). The raw image is the distorted one: a point ``X`` in the optical frame
  (x right, y down, z forward, metres) lands at ``cv2.projectPoints(X, 0, 0, K, D)``.
* :class:`SceneRenderer`: ray-casts, for every pixel centre of the raw image, the synthetic
  scene: textured, shaded tissue height field, pelvic-bone boxes, an optional planar
  calibration target (checkerboard or the D7.2 circular pattern with ArUco markers); the static
  part is rendered once per camera pose and cached, the instrument shafts are drawn per frame.

Units: metres, radians, pixels (pixel centres at integer coordinates, OpenCV convention).
"""
import math

import cv2
import numpy as np

from saras_drivers import rigid


def _matrix(node, rows, cols, name):
    try:
        data = np.asarray(node['data'], dtype=float)
        r, c = int(node.get('rows', rows)), int(node.get('cols', cols))
        return data.reshape(r, c)
    except (KeyError, TypeError, ValueError) as ex:
        raise ValueError('camera_info %s invalid: %s' % (name, ex))


class CameraModel(object):
    """Raw-image camera model (K, D) plus the rectification R and projection P of camera_info."""

    def __init__(self, width, height, K, D, R=None, P=None, distortion_model='plumb_bob',
                 name='camera'):
        self.width, self.height = int(width), int(height)
        self.K = np.asarray(K, dtype=float).reshape(3, 3)
        self.D = np.asarray(D, dtype=float).ravel()
        self.R = np.eye(3) if R is None else np.asarray(R, dtype=float).reshape(3, 3)
        if P is None:
            P = np.hstack([self.K, np.zeros((3, 1))])
        self.P = np.asarray(P, dtype=float).reshape(3, 4)
        self.distortion_model = str(distortion_model)
        self.name = str(name)
        if self.width <= 0 or self.height <= 0:
            raise ValueError('camera_info image size must be positive')
        if not (self.K[0, 0] > 0 and self.K[1, 1] > 0) or not np.all(np.isfinite(self.K)):
            raise ValueError('camera_info camera_matrix needs finite fx, fy > 0')
        if self.distortion_model not in ('plumb_bob', 'rational_polynomial'):
            raise ValueError('camera_info distortion_model %r not supported' % self.distortion_model)
        if not np.all(np.isfinite(self.D)) or not np.all(np.isfinite(self.P)):
            raise ValueError('camera_info distortion/projection must be finite')

    @classmethod
    def from_yaml_dict(cls, d):
        """From the dictionary of a camera_calibration YAML file."""
        try:
            w, h = int(d['image_width']), int(d['image_height'])
        except (KeyError, TypeError, ValueError):
            raise ValueError('camera_info needs image_width and image_height')
        K = _matrix(d.get('camera_matrix', {}), 3, 3, 'camera_matrix')
        Dn = d.get('distortion_coefficients', {'data': [0, 0, 0, 0, 0]})
        D = np.asarray(Dn.get('data', []), dtype=float)
        R = _matrix(d['rectification_matrix'], 3, 3, 'rectification_matrix') \
            if 'rectification_matrix' in d else None
        P = _matrix(d['projection_matrix'], 3, 4, 'projection_matrix') \
            if 'projection_matrix' in d else None
        return cls(w, h, K, D, R, P, d.get('distortion_model', 'plumb_bob'),
                   d.get('camera_name', 'camera'))

    @classmethod
    def from_yaml_file(cls, path):
        import yaml
        try:
            with open(path) as f:
                d = yaml.safe_load(f)
        except (IOError, OSError, yaml.YAMLError) as ex:
            raise ValueError('cannot read camera_info file %s: %s' % (path, ex))
        if not isinstance(d, dict):
            raise ValueError('camera_info file %s is not a YAML mapping' % path)
        return cls.from_yaml_dict(d)

    def to_yaml_dict(self):
        """Dictionary in camera_calibration's YAML layout."""
        def m(a):
            return {'rows': a.shape[0], 'cols': a.shape[1], 'data': [float(v) for v in a.ravel()]}
        return {'image_width': self.width, 'image_height': self.height, 'camera_name': self.name,
                'camera_matrix': m(self.K), 'distortion_model': self.distortion_model,
                'distortion_coefficients': m(self.D.reshape(1, -1)),
                'rectification_matrix': m(self.R), 'projection_matrix': m(self.P)}

    def scaled(self, width, height):
        """Same optics at another resolution (binning/upscaling of the sensor): K, P scale."""
        sx, sy = float(width) / self.width, float(height) / self.height
        S = np.array([[sx, 0.0, 0.5 * sx - 0.5], [0.0, sy, 0.5 * sy - 0.5], [0.0, 0.0, 1.0]])
        return CameraModel(width, height, S @ self.K, self.D, self.R, S @ self.P,
                           self.distortion_model, self.name)

    @property
    def baseline_tx(self):
        """P[0,3] = -fx' * B for the right camera of a stereo pair (0 for the left) [px*m]."""
        return float(self.P[0, 3])

    def project(self, points_cam):
        """Raw-image pixels (N, 2) of optical-frame points (N, 3) [m] (must have z > 0)."""
        pts = np.asarray(points_cam, dtype=np.float64).reshape(-1, 1, 3)
        uv, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), self.K, self.D)
        return uv.reshape(-1, 2)

    def pixel_rays(self, step=1):
        """(h, w, 3) float32 rays (x, y, 1) in the optical frame through pixel centres.

        ``step`` > 1 gives the grid cv2.resize(INTER_LINEAR) expects for an image ``step`` times
        smaller: low-resolution pixel j sits at full-resolution coordinate (j + 0.5) step - 0.5.
        """
        w, h = self.width // step, self.height // step
        us = (np.arange(w) + 0.5) * step - 0.5
        vs = (np.arange(h) + 0.5) * step - 0.5
        u, v = np.meshgrid(us, vs)
        pts = np.stack([u.ravel(), v.ravel()], axis=-1).reshape(-1, 1, 2)
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-12)
        xy = cv2.undistortPointsIter(pts, self.K, self.D, None, None, crit).reshape(-1, 2)
        rays = np.empty((h, w, 3), np.float32)
        rays[..., 0] = xy[:, 0].reshape(h, w)
        rays[..., 1] = xy[:, 1].reshape(h, w)
        rays[..., 2] = 1.0
        return rays

    def field_of_view_bounds(self):
        """Max |x/z|, |y/z| over the image border (normalised coordinates)."""
        b = []
        for u in (0, self.width - 1):
            for v in np.linspace(0, self.height - 1, 9):
                b.append((u, v))
        for v in (0, self.height - 1):
            for u in np.linspace(0, self.width - 1, 9):
                b.append((u, v))
        xy = cv2.undistortPoints(np.asarray(b, np.float64).reshape(-1, 1, 2), self.K, self.D)
        xy = np.abs(xy.reshape(-1, 2))
        return float(xy[:, 0].max()), float(xy[:, 1].max())


# ---------------------------------------------------------------------------------------------
# Scene content
# ---------------------------------------------------------------------------------------------

def tissue_texture(size=1024, seed=7):
    """Procedural BGR tissue texture (pink mucosa, blobs, vessels), deterministic."""
    rng = np.random.default_rng(seed)
    base = np.array([120, 110, 200], np.float32)  # BGR pink
    img = np.empty((size, size, 3), np.float32)
    img[:] = base
    for scale, amp in ((8, 35.0), (32, 18.0), (128, 8.0)):
        n = rng.standard_normal((scale, scale)).astype(np.float32)
        n = cv2.resize(n, (size, size), interpolation=cv2.INTER_CUBIC)
        img += amp * n[..., None] * np.array([0.6, 0.8, 1.0], np.float32)
    vessels = np.zeros((size, size), np.uint8)
    for _ in range(40):
        p = rng.uniform(0, size, 2)
        ang = rng.uniform(0, 2 * math.pi)
        pts = []
        for _ in range(30):
            ang += rng.normal(0, 0.25)
            p = p + 12.0 * np.array([math.cos(ang), math.sin(ang)])
            pts.append(p.copy())
        cv2.polylines(vessels, [np.int32(pts).reshape(-1, 1, 2)], False, 255,
                      int(rng.integers(1, 4)), cv2.LINE_AA)
    vessels = cv2.GaussianBlur(vessels, (5, 5), 0).astype(np.float32)[..., None] / 255.0
    img = img * (1.0 - 0.55 * vessels) + vessels * 0.55 * np.array([40, 30, 130], np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


def load_boxes(path, scaling=1.0):
    """Pelvic-bone boxes from saras_collision's vertices file: first number NUM, then NUM x 8
    lines ``x y z`` in ``bones_marker_frame`` ('#' starts a comment), times ``scaling`` (file unit
    -> metres, as saras_collision's ``scaling``). Returns a list of (8, 3) arrays [m]."""
    with open(path) as f:
        tokens = ' '.join(line.split('#', 1)[0] for line in f).split()
    if not tokens:
        raise ValueError('%s: empty vertices file' % path)
    try:
        num = int(tokens[0])
        vals = np.asarray([float(t) for t in tokens[1:]], dtype=float) * float(scaling)
    except ValueError as ex:
        raise ValueError('%s: not numeric: %s' % (path, ex))
    if num < 0 or vals.size != num * 24 or not np.all(np.isfinite(vals)):
        raise ValueError('%s: expected %d boxes x 8 vertices x 3 finite numbers, got %d numbers'
                         % (path, num, vals.size))
    return [vals[24 * i:24 * (i + 1)].reshape(8, 3) for i in range(num)]


def box_from_vertices(v):
    """Oriented box (centre (3,), axes (3, 3) rows = unit axes, half extents (3,)) of 8 vertices.

    The three edges at vertex 0 are its three nearest vertices when the vertices form a box (in
    any order); if they are not orthogonal, the principal axes of the vertex cloud are used.
    """
    v = np.asarray(v, dtype=float)
    c = v.mean(axis=0)
    d = np.linalg.norm(v[1:] - v[0], axis=1)
    e = v[1:][np.argsort(d)[:3]] - v[0]
    n = np.linalg.norm(e, axis=1)
    axes = e / np.maximum(n[:, None], 1e-12)
    if np.all(n > 1e-9) and np.max(np.abs(axes @ axes.T - np.eye(3))) < 1e-3:
        return c, axes, n / 2.0
    _, _, vt = np.linalg.svd(v - c)
    proj = (v - c) @ vt.T
    lo, hi = proj.min(axis=0), proj.max(axis=0)
    return c + vt.T @ ((lo + hi) / 2.0), vt, (hi - lo) / 2.0


def clip_polygon_near(poly, near):
    """Sutherland-Hodgman clip of a 3D polygon (N, 3) (camera frame) to the half space z >= near."""
    out = []
    n = len(poly)
    for e in range(n):
        cur, prev = poly[e], poly[e - 1]
        cin, pin = cur[2] >= near, prev[2] >= near
        if cin != pin:
            a = (near - prev[2]) / (cur[2] - prev[2])
            out.append(prev + a * (cur - prev))
        if cin:
            out.append(cur)
    return np.array(out).reshape(-1, 3)


def clip_polygon(poly, xmax, ymax):
    """Sutherland-Hodgman clip of a 2D polygon (N, 2) to the rectangle |x| <= xmax, |y| <= ymax."""
    out = [np.asarray(p, float) for p in poly]
    for axis, sign, lim in ((0, 1, xmax), (0, -1, xmax), (1, 1, ymax), (1, -1, ymax)):
        inp, out = out, []
        if not inp:
            break
        prev = inp[-1]
        for cur in inp:
            cin, pin = sign * cur[axis] <= lim, sign * prev[axis] <= lim
            if cin != pin:
                a = (lim - sign * prev[axis]) / (sign * (cur[axis] - prev[axis]))
                out.append(prev + a * (cur - prev))
            if cin:
                out.append(cur)
            prev = cur
    return np.array(out).reshape(-1, 2)


class PlanarTarget(object):
    """A printed calibration board: grayscale texture on the board plane (z = 0 of its frame).

    ``texture`` uint8 (rows, cols), texel size ``res`` [m]; texel (j, i) centre is at board
    coordinates ``(x_min + (i + 0.5) res, y_min + (j + 0.5) res)``. ``points`` are the feature
    points (board frame, (N, 3)) a detector should find (checkerboard inner corners / dot centres).
    """

    def __init__(self, kind, texture, res, x_min, y_min, points, marker_corners=None):
        self.kind = kind
        self.texture = texture
        self.res = float(res)
        self.x_min, self.y_min = float(x_min), float(y_min)
        self.points = np.asarray(points, dtype=float)
        self.marker_corners = marker_corners or {}

    @property
    def x_max(self):
        return self.x_min + self.texture.shape[1] * self.res

    @property
    def y_max(self):
        return self.y_min + self.texture.shape[0] * self.res

    @classmethod
    def checkerboard(cls, cols=8, rows=6, square=0.008, res=0.0001):
        """``cols`` x ``rows`` inner corners, squares of ``square`` [m]; origin at the first inner
        corner, corners at ``(i * square, j * square, 0)`` as OpenCV object points."""
        k = int(round(square / res))
        if k < 2 or abs(k * res - square) > 1e-9:
            raise ValueError('checkerboard square must be a multiple (>= 2) of the texel size')
        margin = 1
        nx, ny = cols + 1 + 2 * margin, rows + 1 + 2 * margin  # squares incl. white margin
        tex = np.full((ny * k, nx * k), 255, np.uint8)
        for j in range(rows + 1):
            for i in range(cols + 1):
                if (i + j) % 2 == 0:
                    y0, x0 = (j + margin) * k, (i + margin) * k
                    tex[y0:y0 + k, x0:x0 + k] = 0
        x_min = y_min = -(1 + margin) * square
        pts = [(i * square, j * square, 0.0) for j in range(rows) for i in range(cols)]
        return cls('checkerboard', tex, res, x_min, y_min, pts)

    @classmethod
    def circles(cls, dot_circle_radius=0.100, dot_diameter=0.005, dots=8,
                marker_circle_radius=0.060, marker_side=0.025, res=0.0002, dictionary='DICT_4X4_50'):
        """The D7.2 positioner board (Section 4.3): ``dots`` black dots of ``dot_diameter`` on a
        circle of radius ``dot_circle_radius``; four ArUco markers (ids 0-3) of side ``marker_side``
        centred on a concentric circle of radius ``marker_circle_radius`` at 45, 135, 225, 315 deg,
        axis-aligned. Origin at the circle centre. ``points`` = dot centres."""
        half = dot_circle_radius + dot_diameter + 0.01
        n = int(math.ceil(2 * half / res))
        tex = np.full((n, n), 255, np.uint8)
        x_min = y_min = -n * res / 2.0

        def to_px(x, y):
            return (x - x_min) / res - 0.5, (y - y_min) / res - 0.5
        sh = 4  # sub-pixel bits for cv2 drawing
        pts = []
        for i in range(int(dots)):
            a = 2 * math.pi * i / dots
            x, y = dot_circle_radius * math.cos(a), dot_circle_radius * math.sin(a)
            pts.append((x, y, 0.0))
            u, v = to_px(x, y)
            cv2.circle(tex, (int(round(u * 16)), int(round(v * 16))),
                       int(round(dot_diameter / 2 / res * 16)), 0, -1, cv2.LINE_AA, sh)
        aruco = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
        side_px = int(round(marker_side / res))
        corners = {}
        for mid in range(4):
            a = math.pi / 4 + mid * math.pi / 2
            cx, cy = marker_circle_radius * math.cos(a), marker_circle_radius * math.sin(a)
            img = cv2.aruco.drawMarker(aruco, mid, side_px) if hasattr(cv2.aruco, 'drawMarker') \
                else cv2.aruco.generateImageMarker(aruco, mid, side_px)
            u0 = int(round((cx - marker_side / 2 - x_min) / res))
            v0 = int(round((cy - marker_side / 2 - y_min) / res))
            tex[v0:v0 + side_px, u0:u0 + side_px] = img
            xm, ym = x_min + u0 * res, y_min + v0 * res
            s = side_px * res
            corners[mid] = np.array([(xm, ym, 0), (xm + s, ym, 0), (xm + s, ym + s, 0), (xm, ym + s, 0)])
        return cls('circles', tex, res, x_min, y_min, pts, corners)


class SceneRenderer(object):
    """Renders raw (distorted) BGR images of the synthetic surgical scene for one camera.

    ``surface``: TissueSurface (world frame). ``boxes``: list of (8, 3) vertex arrays in world.
    ``target``: optional (PlanarTarget, T_world_board). The static layer (tissue, bones, target)
    is cached per camera pose; :meth:`render` adds the instrument shafts.
    """

    def __init__(self, camera, surface, boxes=(), target=None, texture_size=1024,
                 texture_extent=0.30, light_distance=0.10, tissue_iterations=6,
                 tissue_subsample=4):
        self.cam = camera
        self.surface = surface
        self.rays = camera.pixel_rays()
        self.ray_norm = np.linalg.norm(self.rays, axis=2)
        self.rays_lo = camera.pixel_rays(int(tissue_subsample))
        self.fov = camera.field_of_view_bounds()
        self.iterations = int(tissue_iterations)
        self.light_distance = float(light_distance)
        # Precomputed tissue maps over a square of side texture_extent centred on the surface centre.
        self.tex = tissue_texture(texture_size)
        self.tex_res = float(texture_extent) / texture_size
        self.tex_x0 = surface.cx - texture_extent / 2.0
        self.tex_y0 = surface.cy - texture_extent / 2.0
        g = self.tex_x0 + (np.arange(texture_size) + 0.5) * self.tex_res
        gy = self.tex_y0 + (np.arange(texture_size) + 0.5) * self.tex_res
        X, Y = np.meshgrid(g, gy)
        self.hmap = surface.height(X, Y).astype(np.float32)
        self.nmap = surface.normal(X, Y).astype(np.float32)
        self.boxes = [box_from_vertices(b) for b in boxes]
        self.target = None
        self.set_target(target)
        self._cache_pose = None
        self._cache = None
        self.background_renders = 0

    def set_boxes(self, boxes):
        """Replace the bone boxes (list of (8, 3) vertex arrays in world [m])."""
        self.boxes = [box_from_vertices(b) for b in boxes]
        self._cache_pose = None

    def set_target(self, target):
        """Show (PlanarTarget, T_world_board) or hide (None) the calibration target."""
        self.target = target
        self._cache_pose = None

    # -- static layer ---------------------------------------------------------------------
    def _tex_coords(self, x, y):
        return ((x - self.tex_x0) / self.tex_res - 0.5).astype(np.float32), \
               ((y - self.tex_y0) / self.tex_res - 0.5).astype(np.float32)

    def render_background(self, T_world_cam):
        """(image BGR uint8 (H, W, 3), depth along optical z [m] float32 (H, W), inf = nothing).

        The tissue geometry (ray/height-field intersection, texture coordinates, shading) is
        smooth, so it is solved on a grid ``tissue_subsample`` times coarser and interpolated;
        the texture itself, bones and calibration targets are sampled at every pixel centre.
        """
        R = T_world_cam[:3, :3].astype(np.float32)
        o = T_world_cam[:3, 3].astype(np.float32)
        H, W = self.cam.height, self.cam.width
        h, w = self.rays_lo.shape[:2]
        d = (self.rays_lo.reshape(-1, 3) @ R.T).reshape(h, w, 3)
        dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
        # Tissue: fixed-point iteration t <- (h(o + t d) - o_z) / d_z on rays pointing down.
        down = dz < -1e-6
        dzs = np.where(down, dz, np.float32(-1.0))
        t = (np.float32(self.surface.z0) - o[2]) / dzs
        for _ in range(self.iterations):
            mx, my = self._tex_coords(o[0] + t * dx, o[1] + t * dy)
            hh = cv2.remap(self.hmap, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            t = (hh - o[2]) / dzs
        hit = (down & (t > 0)).astype(np.float32)
        mx, my = self._tex_coords(o[0] + t * dx, o[1] + t * dy)
        nrm = cv2.remap(self.nmap, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        dn = np.sqrt(dx * dx + dy * dy + dz * dz)
        lam = np.clip(-(nrm[..., 0] * dx + nrm[..., 1] * dy + nrm[..., 2] * dz) / dn, 0.0, 1.0)
        fall = np.clip((self.light_distance / np.maximum(t * dn, 1e-3)) ** 1.5, 0.3, 1.3)
        shade = ((0.15 + 0.85 * lam) * fall * hit).astype(np.float32)
        up = (W, H)
        mx = cv2.resize(mx, up, interpolation=cv2.INTER_LINEAR)
        my = cv2.resize(my, up, interpolation=cv2.INTER_LINEAR)
        shade = cv2.resize(shade, up, interpolation=cv2.INTER_LINEAR)
        tfull = cv2.resize(np.where(hit > 0, t, np.float32(0)), up, interpolation=cv2.INTER_LINEAR)
        hitf = cv2.resize(hit, up, interpolation=cv2.INTER_LINEAR) > 0.999
        col = cv2.remap(self.tex, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        # uint8 all the way: shade in 1/128 steps (saturating), texture * shade / 128.
        shade8 = cv2.cvtColor(cv2.convertScaleAbs(shade, alpha=128.0), cv2.COLOR_GRAY2BGR)
        img = cv2.multiply(col, shade8, scale=1.0 / 128.0)
        depth = np.where(hitf, tfull, np.float32(np.inf)).astype(np.float32)
        # Bone boxes: exact ray/box slab test on the pixels of their projected bounding rectangle.
        for centre, axes, half in self.boxes:
            self._render_box(img, depth, T_world_cam, R, o, centre, axes, half)
        if self.target is not None:
            self._render_target(img, depth, T_world_cam, R, o)
        return img, depth

    def _roi(self, T_world_cam, pts_world):
        """Pixel rectangle (x0, y0, x1, y1) covering the convex hull of world points, or None.

        The hull's normalised-coordinate bounding box is clipped to the field of view before
        projection (points far outside the image cannot be projected through the distortion
        polynomial); a hull that straddles the camera plane gets the whole image.
        """
        Tcw = rigid.invert(T_world_cam)
        pc = pts_world @ Tcw[:3, :3].T + Tcw[:3, 3]
        near = 1e-4
        if np.all(pc[:, 2] <= near):
            return None
        if np.any(pc[:, 2] <= near):
            return 0, 0, self.cam.width, self.cam.height
        xy = pc[:, :2] / pc[:, 2:3]
        fx, fy = self.fov
        lo = np.maximum(xy.min(axis=0), [-1.02 * fx, -1.02 * fy])
        hi = np.minimum(xy.max(axis=0), [1.02 * fx, 1.02 * fy])
        if np.any(lo > hi):
            return None
        s = np.linspace(0.0, 1.0, 9)
        border = np.concatenate([
            np.stack([lo[0] + s * (hi[0] - lo[0]), np.full_like(s, lo[1])], -1),
            np.stack([lo[0] + s * (hi[0] - lo[0]), np.full_like(s, hi[1])], -1),
            np.stack([np.full_like(s, lo[0]), lo[1] + s * (hi[1] - lo[1])], -1),
            np.stack([np.full_like(s, hi[0]), lo[1] + s * (hi[1] - lo[1])], -1)])
        uv = self.cam.project(np.column_stack([border, np.ones(len(border))]))
        x0, y0 = np.floor(uv.min(axis=0)).astype(int) - 3
        x1, y1 = np.ceil(uv.max(axis=0)).astype(int) + 4
        x0, y0 = max(x0, 0), max(y0, 0)
        x1, y1 = min(x1, self.cam.width), min(y1, self.cam.height)
        if x0 >= x1 or y0 >= y1:
            return None
        return x0, y0, x1, y1

    def _render_box(self, img, depth, T_world_cam, R, o, centre, axes, half):
        """Box by its camera-facing faces: each face, clipped to z >= 1 mm and to the field of
        view, has its outline (edges sampled through the distortion model) filled; every covered
        pixel's ray is intersected with the face plane (exact depth, per-pixel Lambert shading)
        and z-tested against the depth buffer."""
        Tcw = rigid.invert(T_world_cam)
        o64 = o.astype(np.float64)
        fxb, fyb = self.fov
        H, W = self.cam.height, self.cam.width
        s = np.linspace(0.0, 1.0, 9)[:-1]  # edge samples (distorted images bend straight edges)
        jobs = []
        for i in range(3):
            j, k = (i + 1) % 3, (i + 2) % 3
            for sign in (-1.0, 1.0):
                n = sign * axes[i]
                fc = centre + sign * half[i] * axes[i]
                if np.dot(n, o64 - fc) <= 0.0:
                    continue  # back face
                quad = np.array([fc + a * half[j] * axes[j] + b * half[k] * axes[k]
                                 for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
                qc = clip_polygon_near(quad @ Tcw[:3, :3].T + Tcw[:3, 3], 1e-3)
                if len(qc) < 3:
                    continue
                # Straight lines stay straight on the normalised plane: clip there to the field
                # of view, then sample the outline through the distortion model.
                poly = clip_polygon(qc[:, :2] / qc[:, 2:3], 1.03 * fxb, 1.03 * fyb)
                if len(poly) < 3:
                    continue
                m = len(poly)
                pts = np.concatenate([poly[e] + s[:, None] * (poly[(e + 1) % m] - poly[e])
                                      for e in range(m)])
                jobs.append((n, fc, axes[j], half[j], axes[k], half[k],
                             self.cam.project(np.column_stack([pts, np.ones(len(pts))]))))
        bone = np.array([190, 215, 230], np.float32)
        for n, fc, aj, hj, ak, hk, uv in jobs:
            x0, y0 = np.maximum(np.floor(uv.min(axis=0)).astype(int) - 1, 0)
            x1, y1 = np.minimum(np.ceil(uv.max(axis=0)).astype(int) + 2, [W, H])
            if x0 >= x1 or y0 >= y1:
                continue
            mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
            poly = np.round((uv - [x0, y0]) * 16).astype(np.int32).reshape(-1, 1, 2)
            cv2.fillPoly(mask, [poly], 255, cv2.LINE_8, 4)
            # conservative candidate set; the exact in-face test below decides edge pixels
            cand = cv2.dilate(mask, np.ones((3, 3), np.uint8)) > 0
            # Dense over the face's rectangle, in the camera frame (ray = (x, y, 1), t = depth).
            Rt = R.T.astype(np.float64)
            nc, ajc, akc = Rt @ n, Rt @ aj, Rt @ ak
            rel = Rt @ (o64 - fc)
            rx, ry = self.rays[y0:y1, x0:x1, 0], self.rays[y0:y1, x0:x1, 1]
            nd = rx * np.float32(nc[0]) + ry * np.float32(nc[1]) + np.float32(nc[2])
            with np.errstate(divide='ignore', invalid='ignore'):
                t = np.float32(-np.dot(nc, rel)) / nd
            dsub = depth[y0:y1, x0:x1]
            ok = cand & (nd < 0) & (t > 0) & (t < dsub)
            u = np.float32(rel @ ajc) + t * (rx * np.float32(ajc[0]) + ry * np.float32(ajc[1]) +
                                             np.float32(ajc[2]))
            v = np.float32(rel @ akc) + t * (rx * np.float32(akc[0]) + ry * np.float32(akc[1]) +
                                             np.float32(akc[2]))
            ok &= (np.abs(u) <= hj * (1 + 1e-5)) & (np.abs(v) <= hk * (1 + 1e-5))
            if not np.any(ok):
                continue
            dn = self.ray_norm[y0:y1, x0:x1]
            fall = np.clip((self.light_distance / np.maximum(t * dn, 1e-3)) ** 1.5, 0.3, 1.3)
            shade = np.clip((0.25 + 0.75 * (-nd / dn)) * fall, 0.0, 1.3)
            colour = cv2.merge([np.clip(c * shade, 0, 255).astype(np.uint8) for c in bone])
            np.copyto(img[y0:y1, x0:x1], colour, where=ok[..., None])
            np.copyto(dsub, t, where=ok)

    def _render_target(self, img, depth, T_world_cam, R, o):
        tgt, T_wb = self.target
        corners = np.array([[x, y, 0.0] for x in (tgt.x_min, tgt.x_max) for y in (tgt.y_min, tgt.y_max)])
        roi = self._roi(T_world_cam, corners @ T_wb[:3, :3].T + T_wb[:3, 3])
        if roi is None:
            return
        x0, y0, x1, y1 = roi
        img = img[y0:y1, x0:x1]
        depth = depth[y0:y1, x0:x1]
        Rbw = T_wb[:3, :3].T
        ob = Rbw @ (o.astype(np.float64) - T_wb[:3, 3])
        H, W = y1 - y0, x1 - x0
        db = self.rays[y0:y1, x0:x1].reshape(-1, 3).astype(np.float64) @ (Rbw @ R).T
        with np.errstate(divide='ignore', invalid='ignore'):
            t = -ob[2] / db[:, 2]
        x = ob[0] + t * db[:, 0]
        y = ob[1] + t * db[:, 1]
        t = t.reshape(H, W)
        x = x.reshape(H, W)
        y = y.reshape(H, W)
        inside = np.isfinite(t) & (t > 0) & (t < depth) & (x >= tgt.x_min) & (x < tgt.x_max) & \
            (y >= tgt.y_min) & (y < tgt.y_max)
        if not np.any(inside):
            return
        mx = ((x - tgt.x_min) / tgt.res - 0.5).astype(np.float32)
        my = ((y - tgt.y_min) / tgt.res - 0.5).astype(np.float32)
        val = cv2.remap(tgt.texture, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        v = (val[inside].astype(np.float32) * 0.85 + 20.0).astype(np.uint8)  # matte paper
        img[inside] = v[:, None]
        depth[inside] = t[inside]

    # -- per frame ------------------------------------------------------------------------
    def background(self, T_world_cam):
        """Cached static layer for the camera pose (re-rendered when the pose changes)."""
        if self._cache_pose is None or not np.allclose(self._cache_pose, T_world_cam, atol=1e-7):
            self._cache = self.render_background(T_world_cam)
            self._cache_pose = np.array(T_world_cam, copy=True)
            self.background_renders += 1
        return self._cache

    def render(self, T_world_cam, tools=(), out=None):
        """Full frame: cached static layer + instrument shafts.

        ``tools``: iterable of (tip_world (3,), rcm_world (3,), radius [m]); the shaft runs from
        the tip towards the RCM; parts below the tissue surface or behind the camera are hidden.
        Returns the BGR image (``out`` reused if given).
        """
        bg, _ = self.background(T_world_cam)
        if out is None or out.shape != bg.shape:
            out = bg.copy()
        else:
            np.copyto(out, bg)
        Tcw = rigid.invert(T_world_cam)
        items = []
        for tip, rcm, radius in tools:
            tip = np.asarray(tip, float)
            rcm = np.asarray(rcm, float)
            if not (np.all(np.isfinite(tip)) and np.all(np.isfinite(rcm))):
                continue
            s = np.linspace(0.0, 1.0, 16)[:, None]
            pw = tip + s * (rcm - tip)
            pw = np.vstack([pw, rcm + 0.25 * (rcm - tip)])  # shaft continues outside the trocar
            above = pw[:, 2] >= self.surface.height(pw[:, 0], pw[:, 1]) - 1e-4
            pc = pw @ Tcw[:3, :3].T + Tcw[:3, 3]
            items.append((float(np.min(pc[:, 2])), pc, above, float(radius)))
        # Painter's order: farthest shaft first.
        for _, pc, above, radius in sorted(items, key=lambda it: -it[0]):
            self._draw_shaft(out, pc, above, radius)
        return out

    def _draw_shaft(self, img, pc, above, radius):
        """Shaft as a filled strip between the projected silhouette edges (+ a specular line)."""
        fxb, fyb = self.fov
        ok = above & (pc[:, 2] > 0.003)
        with np.errstate(divide='ignore', invalid='ignore'):
            ok &= (np.abs(pc[:, 0] / pc[:, 2]) < 2.0 * fxb) & (np.abs(pc[:, 1] / pc[:, 2]) < 2.0 * fyb)
        f = self.cam.K[0, 0]
        # Longest run of consecutive visible samples starting nearest to the tip.
        idx = np.flatnonzero(ok)
        if len(idx) < 2:
            return
        run = [idx[0]]
        for i in idx[1:]:
            if i != run[-1] + 1:
                break
            run.append(i)
        if len(run) < 2:
            return
        p = pc[run]
        uv = self.cam.project(p)
        half = f * radius / p[:, 2]
        tang = np.gradient(uv, axis=0)
        nrm = np.stack([-tang[:, 1], tang[:, 0]], axis=-1)
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-9)
        left = uv + nrm * half[:, None]
        right = uv - nrm * half[:, None]
        poly = np.vstack([left, right[::-1]])
        if not np.all(np.isfinite(poly)) or np.abs(poly).max() > 1e5:
            return
        cv2.fillPoly(img, [np.int32(np.round(poly * 16)).reshape(-1, 1, 2)], (105, 108, 112),
                     cv2.LINE_AA, 4)
        cv2.circle(img, tuple(int(round(c * 16)) for c in uv[0]), int(round(half[0] * 16)),
                   (60, 60, 62), -1, cv2.LINE_AA, 4)
        hl = uv + nrm * (0.35 * half[:, None])
        w = int(max(1, round(0.3 * np.median(half))))
        cv2.polylines(img, [np.int32(np.round(hl * 16)).reshape(-1, 1, 2)], False, (190, 192, 195),
                      w, cv2.LINE_AA, 4)
