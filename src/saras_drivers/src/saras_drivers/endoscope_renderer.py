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

    def distort(self, xy):
        """Raw-image pixels (N, 2) of normalised coordinates (N, 2) (x/z, y/z): the OpenCV
        plumb_bob / rational_polynomial model, as cv2.projectPoints (fx, fy, cx, cy; no skew).
        Vectorised numpy (cv2.projectPoints has a high per-call cost for a few points)."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        D = np.zeros(8)
        n = min(len(self.D), 8)
        D[:n] = self.D[:n]
        if len(self.D) > 8 and np.any(self.D[8:] != 0):
            return self.project(np.column_stack([xy, np.ones(len(xy))]))
        k1, k2, p1, p2, k3, k4, k5, k6 = D
        x, y = xy[:, 0], xy[:, 1]
        r2 = x * x + y * y
        radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        return np.column_stack([self.K[0, 0] * xd + self.K[0, 2], self.K[1, 1] * yd + self.K[1, 2]])

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
    out = [(float(p[0]), float(p[1])) for p in poly]   # plain floats: few points, called per frame
    for axis, sign, lim in ((0, 1, xmax), (0, -1, xmax), (1, 1, ymax), (1, -1, ymax)):
        inp, out = out, []
        if not inp:
            break
        prev = inp[-1]
        for cur in inp:
            cin, pin = sign * cur[axis] <= lim, sign * prev[axis] <= lim
            if cin != pin:
                a = (lim - sign * prev[axis]) / (sign * (cur[axis] - prev[axis]))
                out.append((prev[0] + a * (cur[0] - prev[0]), prev[1] + a * (cur[1] - prev[1])))
            if cin:
                out.append(cur)
            prev = cur
    return np.array(out, dtype=float).reshape(-1, 2)


#: corner sign table of an oriented box: row b = signs of axes (0, 1, 2) from the bits of b
_BOX_CORNER_SIGNS = np.array([[1.0 if (b >> i) & 1 else -1.0 for i in range(3)] for b in range(8)])
#: corner indices of face (axis i, sign), ordered around the face: (-,-), (+,-), (+,+), (-,+) in
#: the two other axes (i + 1) % 3, (i + 2) % 3
_BOX_FACES = {(i, sg): [sum(((1 if bits[a] > 0 else 0) << a) for a in range(3))
                        for bits in [{i: sg, (i + 1) % 3: u, (i + 2) % 3: v}
                                     for u, v in ((-1, -1), (1, -1), (1, 1), (-1, 1))]]
              for i in range(3) for sg in (-1.0, 1.0)}
#: the six faces as (axis, sign) and their corner indices (6, 4) for the vectorised box pass
_FACE_KEYS = [(i, sg) for i in range(3) for sg in (-1.0, 1.0)]
_FACE_IDX = np.array([_BOX_FACES[k] for k in _FACE_KEYS])
#: edge sampling fractions for projected outlines
_EDGE_SAMPLES = np.linspace(0.0, 1.0, 9)[:-1]


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


def tissue_grid_steps(width):
    """Default (tissue_subsample, tissue_colour_subsample) [px] for an image ``width`` px wide.

    The tissue content has a fixed angular bandwidth (a 1024-texel texture over 0.30 m: one
    texel is ~1.3 px of the 1280-px, 71-deg camera at the working distance), so its sampling
    grids keep a fixed angular pitch: colour every 2 px at 1280 (and below), 3 px at 1920, ...;
    geometry twice coarser. Bones, shafts and targets stay per pixel at every resolution."""
    colour = max(2, int(round(2.0 * width / 1280.0)))
    return 2 * colour, colour


class SceneRenderer(object):
    """Renders raw (distorted) BGR images of the synthetic surgical scene for one camera.

    ``surface``: TissueSurface (world frame). ``boxes``: list of (8, 3) vertex arrays in world.
    ``target``: optional (PlanarTarget, T_world_board). The static layer (tissue, bones, target)
    is cached per camera pose; :meth:`render` adds the instrument shafts.
    ``tissue_subsample`` / ``tissue_colour_subsample`` [px]: grid steps of the tissue geometry
    and colour (None: :func:`tissue_grid_steps` of the image width).
    """

    def __init__(self, camera, surface, boxes=(), target=None, texture_size=1024,
                 texture_extent=0.30, light_distance=0.10, tissue_iterations=6,
                 tissue_subsample=None, tissue_colour_subsample=None):
        self.cam = camera
        auto = tissue_grid_steps(camera.width)
        tissue_subsample = auto[0] if tissue_subsample is None else tissue_subsample
        tissue_colour_subsample = auto[1] if tissue_colour_subsample is None else tissue_colour_subsample
        self.surface = surface
        self.rays = camera.pixel_rays()
        # contiguous per-component copies for the per-face passes (float32)
        self.rays_x = np.ascontiguousarray(self.rays[..., 0])
        self.rays_y = np.ascontiguousarray(self.rays[..., 1])
        tissue_subsample = int(tissue_subsample)
        tissue_colour_subsample = int(tissue_colour_subsample)
        if tissue_subsample < 1 or tissue_colour_subsample < 1 or \
                tissue_subsample % tissue_colour_subsample:
            raise ValueError('tissue_subsample must be a positive multiple of '
                             'tissue_colour_subsample (>= 1)')
        self._tissue_step = tissue_subsample
        self.rays_lo = camera.pixel_rays(tissue_subsample)
        self.rays_lo_norm = np.linalg.norm(self.rays_lo, axis=2).astype(np.float32)
        # coarse-to-fine tissue solve: iterations on a 2x coarser grid, then refine_iterations
        # here (None: everything on rays_lo, for small images)
        lo_h, lo_w = self.rays_lo.shape[:2]
        self.rays_c = camera.pixel_rays(2 * tissue_subsample) \
            if (lo_w % 2 == 0 and lo_h % 2 == 0 and lo_w >= 160) else None
        self.refine_iterations = 3
        # Tissue colour (texture x shading) is sampled on a grid tissue_colour_subsample times
        # coarser than the image (the texture is magnified ~2x at the working distance anyway)
        # and upsampled: same pixel-centre convention as cv2.resize, so features stay in place.
        self.colour_step = tissue_colour_subsample
        self.colour_size = (camera.width // tissue_colour_subsample,
                            camera.height // tissue_colour_subsample)
        self.fov = camera.field_of_view_bounds()
        self.iterations = int(tissue_iterations)
        self.light_distance = float(light_distance)
        # Precomputed tissue maps over a square of side texture_extent centred on the surface centre.
        self.tex = tissue_texture(texture_size)
        # the texture padded by half its size on each side with its own reflection (what
        # BORDER_REFLECT samples there): ECM views reach ~0.5 texture sizes beyond the textured
        # square, and cv2.remap is ~1.5x slower on samples outside its source image
        self.tex_pad = texture_size // 2
        self.tex_padded = cv2.copyMakeBorder(self.tex, *([self.tex_pad] * 4), cv2.BORDER_REFLECT)
        self.tex_res = float(texture_extent) / texture_size
        self.tex_x0 = surface.cx - texture_extent / 2.0
        self.tex_y0 = surface.cy - texture_extent / 2.0
        g = self.tex_x0 + (np.arange(texture_size) + 0.5) * self.tex_res
        gy = self.tex_y0 + (np.arange(texture_size) + 0.5) * self.tex_res
        X, Y = np.meshgrid(g, gy)
        self.hmap = surface.height(X, Y).astype(np.float32)
        self.nmap = surface.normal(X, Y).astype(np.float32)
        self._scratch = None
        self.set_boxes(boxes)
        self.target = None
        self.set_target(target)
        self._cache_pose = None
        self._cache = None
        self.background_renders = 0
        self._bone_bgr = (190.0, 215.0, 230.0, 0.0)   # bone colour (BGR) at shade 1

    def set_boxes(self, boxes):
        """Replace the bone boxes (list of (8, 3) vertex arrays in world [m])."""
        self.boxes = [box_from_vertices(b) for b in boxes]
        self._bx = None
        if self.boxes:   # stacked for the vectorised pass: corners, face normals/centres/offsets
            C = np.array([b[0] for b in self.boxes])
            A = np.array([b[1] for b in self.boxes])
            Hf = np.array([b[2] for b in self.boxes])
            corners = C[:, None, :] + np.einsum('bkj,bji->bki', _BOX_CORNER_SIGNS[None] * Hf[:, None, :], A)
            ax_i = np.array([i for i, _ in _FACE_KEYS])
            sg = np.array([sg for _, sg in _FACE_KEYS])
            normals = sg[None, :, None] * A[:, ax_i, :]                      # (nb, 6, 3)
            centres = C[:, None, :] + (sg[None, :] * Hf[:, ax_i])[..., None] * A[:, ax_i, :]
            self._bx = {'corners': corners, 'normals': normals, 'centres': centres,
                        'offsets': np.einsum('bfj,bfj->bf', normals, centres)}
        self._cache_pose = None

    def set_target(self, target):
        """Show (PlanarTarget, T_world_board) or hide (None) the calibration target."""
        self.target = target
        self._cache_pose = None

    # -- static layer ---------------------------------------------------------------------
    def _coarse_tissue_depth(self, R, o):
        """Tissue ray depth solved on a grid twice coarser than ``tissue_subsample`` (all
        fixed-point iterations there), upsampled to the tissue grid as its starting point;
        misses (rays not pointing down) start from the mean plane."""
        d = (self.rays_c.reshape(-1, 3) @ R.T).reshape(self.rays_c.shape)
        dz = d[..., 2]
        kz = np.float32(1.0) / np.where(dz < -1e-6, dz, np.float32(-1.0))
        bx = d[..., 0] * np.float32(1.0 / self.tex_res)
        by = d[..., 1] * np.float32(1.0 / self.tex_res)
        ax = np.float32((o[0] - self.tex_x0) / self.tex_res - 0.5)
        ay = np.float32((o[1] - self.tex_y0) / self.tex_res - 0.5)
        t = (np.float32(self.surface.z0) - o[2]) * kz
        for _ in range(self.iterations):
            hh = cv2.remap(self.hmap, t * bx + ax, t * by + ay, cv2.INTER_LINEAR,
                           borderMode=cv2.BORDER_REPLICATE)
            t = (hh - o[2]) * kz
        h, w = self.rays_lo.shape[:2]
        return cv2.resize(t, (w, h), interpolation=cv2.INTER_LINEAR)

    def render_background(self, T_world_cam, with_depth=True):
        """(image BGR uint8 (H, W, 3), depth along optical z [m] float32 (H, W), inf = nothing).

        ``with_depth`` False: depth is None (no full-resolution depth buffer is made; the bone
        z-test upsamples the tissue depth only where the boxes are), unless a target is shown.

        The tissue geometry (ray/height-field intersection, texture coordinates, shading) is
        smooth, so it is solved on a grid ``tissue_subsample`` times coarser and interpolated;
        its colour (texture x shading) is sampled ``tissue_colour_subsample`` times coarser and
        upsampled. Bones and calibration targets are resolved at every pixel centre (exact
        per-pixel depth, sharp outlines).
        """
        R = T_world_cam[:3, :3].astype(np.float32)
        o = T_world_cam[:3, 3].astype(np.float32)
        H, W = self.cam.height, self.cam.width
        h, w = self.rays_lo.shape[:2]
        d = (self.rays_lo.reshape(-1, 3) @ R.T).reshape(h, w, 3)
        dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
        # Tissue: fixed-point iteration t <- (h(o + t d) - o_z) / d_z on rays pointing down,
        # with the texture coordinates (texels) of o + t d affine in t: m = a + t b.
        down = dz < -1e-6
        kz = np.float32(1.0) / np.where(down, dz, np.float32(-1.0))
        inv_res = np.float32(1.0 / self.tex_res)
        ax = np.float32((o[0] - self.tex_x0) / self.tex_res - 0.5)
        ay = np.float32((o[1] - self.tex_y0) / self.tex_res - 0.5)
        bx, by = dx * inv_res, dy * inv_res
        t = self._coarse_tissue_depth(R, o) if self.rays_c is not None else None
        if t is None:   # from the mean plane, all iterations on this grid
            t = (np.float32(self.surface.z0) - o[2]) * kz
            iterations = self.iterations
        else:           # coarse solution upsampled, refined here
            iterations = self.refine_iterations
        mx, my = np.empty_like(t), np.empty_like(t)
        for it in range(iterations + 1):
            np.multiply(t, bx, out=mx)
            mx += ax
            np.multiply(t, by, out=my)
            my += ay
            if it == iterations:
                break
            hh = cv2.remap(self.hmap, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            np.subtract(hh, o[2], out=t)
            t *= kz
        hit = down & (t > 0)
        nrm = cv2.remap(self.nmap, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        dn = self.rays_lo_norm   # |R d| = |d|
        lam = np.clip(-(nrm[..., 0] * dx + nrm[..., 1] * dy + nrm[..., 2] * dz) / dn, 0.0, 1.0)
        x = np.float32(self.light_distance) / np.maximum(t * dn, np.float32(1e-3))
        fall = np.clip(x * np.sqrt(x), 0.3, 1.3)   # (L / distance)^1.5
        # colour layer: texture coordinates + shading (x128, uint8 fixed point) upsampled to the
        # colour grid, texture sampled there, shaded, then upsampled to the image.
        lo = np.empty((h, w, 2), np.float32)
        np.add(mx, np.float32(self.tex_pad), out=lo[..., 0])
        np.add(my, np.float32(self.tex_pad), out=lo[..., 1])
        maps = cv2.resize(lo, self.colour_size, interpolation=cv2.INTER_LINEAR)
        shade = cv2.resize(np.where(hit, (0.15 + 0.85 * lam) * fall * np.float32(128.0),
                                    np.float32(0.0)).astype(np.float32),
                           self.colour_size, interpolation=cv2.INTER_LINEAR)
        col = cv2.remap(self.tex_padded, maps, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        shade = cv2.cvtColor(cv2.convertScaleAbs(shade), cv2.COLOR_GRAY2BGR)
        col = cv2.multiply(col, shade, scale=1.0 / 128.0)
        if self.colour_size != (W, H):
            img = cv2.resize(col, (W, H), interpolation=cv2.INTER_LINEAR)
        else:
            img = col
        # depth: inf where the ray misses the tissue; upsampling marks every pixel that has a
        # missing neighbour on the coarse grid as a miss (inf, or NaN from inf - inf => patched).
        t = np.where(hit, t, np.float32(np.inf))
        depth = None
        if with_depth or self.target is not None:
            depth = cv2.resize(t, (W, H), interpolation=cv2.INTER_LINEAR)
            cv2.patchNaNs(depth, np.inf)
        # Bone boxes: camera-facing faces filled with exact per-pixel depth, z-tested on the
        # inverse depth (0 = nothing), which is linear in the normalised ray coordinates.
        self._render_boxes(img, depth, T_world_cam, t)
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

    def _render_boxes(self, img, depth, T_world_cam, tissue_lo):
        """Bone boxes by their camera-facing faces, all boxes' geometry vectorised.

        Each front face, clipped to z >= 1 mm and to the field of view, has its outline (edges
        sampled through the distortion model) filled with its flat colour (Lambert x head-light
        fall-off at the centroid of its visible part); front faces of a convex box cover
        disjoint image regions. A ray that hits a convex box crosses every front-face plane from
        outside, and enters through the one it meets last, so the box's inverse depth at a
        covered pixel is the smallest front-face plane inverse depth, exact per pixel and linear
        in the normalised ray coordinates (x, y): 1/t = (n . (x, y, 1)) / k. It is z-tested
        against the inverse optical depth of what is already drawn (0 = nothing) and written
        where closer; ``depth`` (None: not wanted) is updated in the rectangle the boxes cover.
        ``tissue_lo``: tissue depth on the tissue grid (inf = miss), upsampled where needed."""
        bx = self._bx
        if bx is None:
            return
        Tcw = rigid.invert(T_world_cam)
        Rcw, tcw = Tcw[:3, :3], Tcw[:3, 3]
        o = np.asarray(T_world_cam[:3, 3], dtype=np.float64)
        fxb, fyb = 1.03 * self.fov[0], 1.03 * self.fov[1]
        H, W = self.cam.height, self.cam.width
        near = 1e-3
        pc = bx['corners'] @ Rcw.T + tcw                      # (nb, 8, 3) camera frame
        z = pc[..., 2]
        ahead = z >= near
        with np.errstate(divide='ignore', invalid='ignore'):
            xz, yz = pc[..., 0] / z, pc[..., 1] / z
        outside = ahead.all(1) & ((xz > fxb).all(1) | (xz < -fxb).all(1) |
                                  (yz > fyb).all(1) | (yz < -fyb).all(1))
        sel = (ahead.any(1) & ~outside)[:, None] & \
            (bx['normals'] @ o - bx['offsets'] > 0.0)           # (nb, 6) visible front faces
        if not sel.any():
            return
        Q = pc[:, _FACE_IDX]                                  # (nb, 6, 4, 3)
        with np.errstate(divide='ignore', invalid='ignore'):
            P = Q[..., :2] / Q[..., 2:3]                      # normalised outlines
        clip_near = (Q[..., 2] < near).any(-1)
        clip_fov = clip_near | (np.abs(P[..., 0]) > fxb).any(-1) | (np.abs(P[..., 1]) > fyb).any(-1)
        nc = bx['normals'] @ Rcw.T                            # (nb, 6, 3) face normals, camera
        kk = np.einsum('bfj,bfj->bf', nc, bx['centres'] @ Rcw.T + tcw)   # plane n . X = kk
        cen = Q.mean(axis=2)                                  # centroid of the visible part
        # faces: (box, face, outline (n, 2) normalised)
        simple = sel & ~clip_fov
        faces = [(b, f, None) for b, f in zip(*np.nonzero(simple))]
        for b, f in zip(*np.nonzero(sel & clip_fov)):
            qc = Q[b, f]
            if clip_near[b, f]:
                qc = clip_polygon_near(qc, near)
                if len(qc) < 3:
                    continue
                cen[b, f] = qc.mean(axis=0)
            poly = qc[:, :2] / qc[:, 2:3]
            poly = clip_polygon(poly, fxb, fyb)
            if len(poly) >= 3:
                faces.append((b, f, poly))
        if not faces:
            return
        faces.sort(key=lambda fc: (fc[0], fc[1]))   # drawing order of a box's faces: axis, sign
        # edges sampled 8 times (distorted images bend straight edges), one distortion call
        polys = [P[b, f] if poly is None else poly for b, f, poly in faces]
        counts = [len(p) for p in polys]
        allp = np.concatenate(polys)
        nxt = np.concatenate([np.roll(p, -1, axis=0) for p in polys])
        pts = (allp[:, None, :] + _EDGE_SAMPLES[None, :, None] * (nxt - allp)[:, None, :]).reshape(-1, 2)
        uv_flat = self.cam.distort(pts)
        bounds = np.cumsum([0] + [8 * c for c in counts])
        fb = np.array([b for b, _, _ in faces])
        ff = np.array([f for _, f, _ in faces])
        # flat shading per face: Lambert at the centroid x head-light fall-off
        c = cen[fb, ff]
        dist = np.maximum(np.linalg.norm(c, axis=1), 1e-3)
        fall = np.clip((self.light_distance / dist) ** 1.5, 0.3, 1.3)
        lam = np.maximum(-np.einsum('fj,fj->f', nc[fb, ff], c) / dist, 0.0)
        shade = np.minimum((0.25 + 0.75 * lam) * fall, 1.3)
        colours = np.clip(np.outer(shade, self._bone_bgr[:3]), 1.0, 255.0)
        planes = nc[fb, ff] / kk[fb, ff][:, None]             # inverse depth = planes . (x, y, 1)
        # per face and per box: pixel rectangles
        per_box = {}
        for i, b in enumerate(fb):
            uv = uv_flat[bounds[i]:bounds[i + 1]]
            if np.all(np.isfinite(uv)):
                fr = (np.floor(uv.min(axis=0)).astype(int) - 2, np.ceil(uv.max(axis=0)).astype(int) + 3)
                per_box.setdefault(b, []).append((uv, i, fr))
        rects = []
        for b, fl in per_box.items():
            x0, y0 = np.maximum(np.min([fr[0] for _, _, fr in fl], axis=0) + 1, 0)
            x1, y1 = np.minimum(np.max([fr[1] for _, _, fr in fl], axis=0) - 1, [W, H])
            if x0 < x1 and y0 < y1:
                rects.append((x0, y0, x1, y1, fl))
        if not rects:
            return
        # inverse depth in the union of the rectangles (0 = nothing)
        ux0, uy0 = min(r[0] for r in rects), min(r[1] for r in rects)
        ux1, uy1 = max(r[2] for r in rects), max(r[3] for r in rects)
        if depth is not None:
            dsub = depth[uy0:uy1, ux0:ux1]
        else:
            dsub = self._tissue_depth_rect(tissue_lo, ux0, uy0, ux1, uy1)
        idepth = np.divide(np.float32(1.0), dsub)
        colour_buf, mask_buf, s_buf, t_buf = self._box_scratch()
        for x0, y0, x1, y1, fl in rects:
            hh, ww = y1 - y0, x1 - x0
            colour, mask = colour_buf[:hh, :ww], mask_buf[:hh, :ww]
            smin, tmp = s_buf[:hh, :ww], t_buf[:hh, :ww]
            mask[...] = 0   # colour needs no clearing: only masked pixels are copied
            if len(fl) > 1:
                smin[...] = np.inf
            for k, (uv, i, (f0, f1)) in enumerate(fl):
                poly = [np.round((uv - [x0, y0]) * 16).astype(np.int32).reshape(-1, 1, 2)]
                cv2.fillPoly(colour, poly, tuple(float(v) for v in colours[i]), cv2.LINE_8, 4)
                cv2.fillPoly(mask, poly, 255, cv2.LINE_8, 4)
                # plane over the face's own rectangle (2 px margin: every pixel fillPoly covers
                # lies in the rectangle of the face it belongs to, whose plane is the smallest)
                fx0, fy0 = max(f0[0], x0), max(f0[1], y0)
                fx1, fy1 = min(f1[0], x1), min(f1[1], y1)
                if fx0 >= fx1 or fy0 >= fy1:
                    continue
                sl = (slice(fy0 - y0, fy1 - y0), slice(fx0 - x0, fx1 - x0))
                a, bb, cc = (float(v) for v in planes[i])
                rx, ry = self.rays_x[fy0:fy1, fx0:fx1], self.rays_y[fy0:fy1, fx0:fx1]
                if len(fl) == 1:
                    cv2.addWeighted(rx, a, ry, bb, cc, dst=smin[sl])
                else:   # smallest plane where face rectangles overlap
                    cv2.addWeighted(rx, a, ry, bb, cc, dst=tmp[sl])
                    cv2.min(smin[sl], tmp[sl], dst=smin[sl])
            isub = idepth[y0 - uy0:y1 - uy0, x0 - ux0:x1 - ux0]
            ok = cv2.bitwise_and(mask, cv2.compare(smin, isub, cv2.CMP_GT))
            cv2.copyTo(colour, ok, img[y0:y1, x0:x1])
            cv2.copyTo(smin, ok, isub)
        if depth is not None:
            with np.errstate(divide='ignore'):
                np.divide(np.float32(1.0), idepth, out=dsub)

    def _tissue_depth_rect(self, t_lo, x0, y0, x1, y1):
        """Full-resolution tissue depth in [y0:y1, x0:x1] from the tissue grid ``t_lo`` (inf =
        miss), equal to that region of the whole-image cv2.resize (+ patchNaNs): a block with
        one grid cell of margin is upsampled by the integer grid step and cropped."""
        s = self._tissue_step
        H, W = self.cam.height, self.cam.width
        h, w = t_lo.shape
        if w * s != W or h * s != H:   # non-integer scale: whole image
            d = cv2.resize(t_lo, (W, H), interpolation=cv2.INTER_LINEAR)
            cv2.patchNaNs(d, np.inf)
            return d[y0:y1, x0:x1]
        j0, i0 = max(y0 // s - 1, 0), max(x0 // s - 1, 0)
        j1, i1 = min(-(-y1 // s) + 1, h), min(-(-x1 // s) + 1, w)
        blk = cv2.resize(t_lo[j0:j1, i0:i1], ((i1 - i0) * s, (j1 - j0) * s),
                         interpolation=cv2.INTER_LINEAR)
        cv2.patchNaNs(blk, np.inf)
        return blk[y0 - j0 * s:y1 - j0 * s, x0 - i0 * s:x1 - i0 * s]

    def _box_scratch(self):
        """Image-sized scratch buffers of the box pass (allocated once per renderer)."""
        if self._scratch is None:
            H, W = self.cam.height, self.cam.width
            self._scratch = (np.empty((H, W, 3), np.uint8), np.empty((H, W), np.uint8),
                             np.empty((H, W), np.float32), np.empty((H, W), np.float32))
        return self._scratch

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
        """Cached static layer (image, depth or None) for the camera pose (re-rendered when the
        pose changes); the full-resolution depth is only made when a target is shown."""
        if self._cache_pose is None or not np.allclose(self._cache_pose, T_world_cam, atol=1e-7):
            self._cache = self.render_background(T_world_cam, with_depth=False)
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
