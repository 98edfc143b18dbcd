"""Core tests of saras_drivers.endoscope_renderer: camera model and projection truth (no roscore)."""
import os

import cv2
import numpy as np
import pytest
import yaml

from saras_drivers import endoscope_renderer as er
from saras_drivers import rigid
from saras_drivers.tissue_surface import TissueSurface

CFG = os.path.join(os.path.dirname(__file__), '..', 'config')


@pytest.fixture(scope='module')
def cams():
    return {eye: er.CameraModel.from_yaml_file(os.path.join(CFG, 'endoscope_%s.yaml' % eye))
            for eye in ('left', 'right')}


def look_at(eye_pos, target, up=(1.0, 0.0, 0.0)):
    """T_world_cam of an optical frame at eye_pos looking at target (independent construction)."""
    z = np.asarray(target, float) - eye_pos
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return rigid.make_transform(np.column_stack([x, y, z]), eye_pos)


def test_shipped_camera_infos_are_a_consistent_stereo_pair(cams):
    left, right = cams['left'], cams['right']
    assert (left.width, left.height) == (right.width, right.height) == (1280, 720)
    np.testing.assert_allclose(left.K, right.K)
    assert left.distortion_model == right.distortion_model == 'plumb_bob'
    assert left.P[0, 3] == 0.0
    baseline = -right.P[0, 3] / right.P[0, 0]
    assert baseline == pytest.approx(0.005, abs=1e-9)   # ~5 mm, the hand-eye frames use the same
    with open(os.path.join(CFG, 'endoscope_left.yaml')) as f:
        d = yaml.safe_load(f)
    assert er.CameraModel.from_yaml_dict(left.to_yaml_dict()).to_yaml_dict() == left.to_yaml_dict()
    assert d['camera_matrix']['data'] == list(left.K.ravel())


def test_bad_camera_info_is_rejected():
    with pytest.raises(ValueError, match='image_width'):
        er.CameraModel.from_yaml_dict({'camera_matrix': {'data': [1] * 9}})
    with pytest.raises(ValueError, match='fx'):
        er.CameraModel(10, 10, np.zeros((3, 3)), [0] * 5)
    with pytest.raises(ValueError, match='distortion_model'):
        er.CameraModel(10, 10, np.eye(3), [0] * 5, distortion_model='fisheye')


def test_pixel_rays_reproject_onto_their_pixels(cams):
    cam = cams['left']
    rays = cam.pixel_rays()
    sel = rays[::37, ::41].reshape(-1, 3).astype(np.float64)
    uv = cam.project(sel)
    v, u = np.mgrid[0:cam.height:37, 0:cam.width:41]
    np.testing.assert_allclose(uv, np.stack([u.ravel(), v.ravel()], -1), atol=2e-3)


def test_scaled_model_projects_consistently(cams):
    cam = cams['left']
    big = cam.scaled(1920, 1080)
    X = np.array([[0.01, -0.02, 0.1], [-0.03, 0.01, 0.12]])
    np.testing.assert_allclose(big.project(X), (cam.project(X) + 0.5) * 1.5 - 0.5, atol=1e-9)


def render_target(cam, target, T_wc, T_wb):
    surf = TissueSurface(z0=-1.0, waves=())
    r = er.SceneRenderer(cam, surf, target=(target, T_wb), texture_size=256)
    return r.render(T_wc)


def test_checkerboard_corners_land_on_their_projection(cams):
    """Projection truth: detected (rendered) corners vs projectPoints(K, D) of the 3D corners."""
    cam = cams['left']
    board = er.PlanarTarget.checkerboard(cols=8, rows=6, square=0.008)
    T_wb = rigid.make_transform(rigid.rpy_to_matrix(np.pi + 0.2, -0.15, 0.4), [0.0, 0.0, 0.0])
    T_wc = look_at(np.array([-0.02, 0.03, 0.11]), [0.028, 0.02, 0.0])
    img = render_target(cam, board, T_wc, T_wb)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    ok, corners = cv2.findChessboardCorners(gray, (8, 6))
    assert ok
    corners = cv2.cornerSubPix(gray, corners, (7, 7), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-4)).reshape(-1, 2)
    T_cb = rigid.invert(T_wc) @ T_wb
    uv = cam.project(board.points @ T_cb[:3, :3].T + T_cb[:3, 3])
    # every projected corner inside the image, matched to a detected corner within 0.3 px
    err = np.linalg.norm(uv[:, None, :] - corners[None], axis=2).min(axis=1)
    assert len(err) == 48 and err.max() < 0.3, err.max()


def test_circular_pattern_markers_and_dots(cams):
    cam = cams['left']
    board = er.PlanarTarget.circles()
    # printed side faces -z of the board frame (OpenCV convention): roll ~pi to face the camera above
    T_wb = rigid.make_transform(rigid.rpy_to_matrix(np.pi + 0.1, 0.05, 0.2), [0.0, 0.0, 0.0])
    T_wc = look_at(np.array([0.0, 0.0, 0.25]), [0.0, 0.0, 0.0])
    img = render_target(cam, board, T_wc, T_wb)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    T_cb = rigid.invert(T_wc) @ T_wb
    proj = lambda P: cam.project(P @ T_cb[:3, :3].T + T_cb[:3, 3])  # noqa: E731
    aruco = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    params = cv2.aruco.DetectorParameters_create()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    corners, ids, _ = cv2.aruco.detectMarkers(gray, aruco, parameters=params)
    assert ids is not None and sorted(ids.ravel().tolist()) == [0, 1, 2, 3]
    for c, i in zip(corners, ids.ravel()):
        expect = proj(board.marker_corners[int(i)])
        assert np.abs(c.reshape(4, 2) - expect).max() < 0.7
    # dot centres: dark blob centroids vs projected centres (5 mm dots, 8 on a 100 mm circle)
    _, bw = cv2.threshold(gray, 100, 255, cv2.THRESH_BINARY_INV)
    n, _, stats, cents = cv2.connectedComponentsWithStats(bw)
    expect = proj(board.points)
    for e in expect:
        d = np.linalg.norm(cents[1:] - e, axis=1)
        j = int(np.argmin(d))
        assert d[j] < 0.5 and 20 < stats[j + 1, cv2.CC_STAT_AREA] < 400


def test_tissue_depth_matches_surface_and_cache():
    cam = er.CameraModel(320, 180, [[240, 0, 159.5], [0, 240, 89.5], [0, 0, 1]], [-0.1, 0.02, 0, 0, 0])
    surf = TissueSurface(z0=0.07)
    r = er.SceneRenderer(cam, surf, texture_size=1024)
    T_wc = look_at(np.array([0.08, 0.0, 0.17]), [0.0, 0.0, 0.07])
    img, depth = r.render_background(T_wc)
    rays = cam.pixel_rays()
    v, u = np.mgrid[5:175:17, 7:315:23]
    for vv, uu in zip(v.ravel(), u.ravel()):
        p = T_wc[:3, :3] @ (rays[vv, uu] * depth[vv, uu]) + T_wc[:3, 3]
        assert abs(p[2] - surf.height(p[0], p[1])) < 2e-4    # on the analytic surface
    assert img.mean() > 40
    r.render(T_wc)
    r.render(T_wc)
    assert r.background_renders == 1
    r.render(look_at(np.array([0.081, 0.0, 0.17]), [0.0, 0.0, 0.07]))
    assert r.background_renders == 2


def test_bone_box_renders_at_its_projection_with_exact_depth():
    cam = er.CameraModel(320, 240, [[250, 0, 159.5], [0, 250, 119.5], [0, 0, 1]], [0] * 5)
    box = np.array([[x, y, z] for x in (-0.01, 0.01) for y in (-0.01, 0.01) for z in (0.0, 0.02)])
    r = er.SceneRenderer(cam, TissueSurface(z0=-1.0, waves=()), boxes=[box], texture_size=128)
    T_wc = look_at(np.array([0.0, 0.0, 0.12]), [0.0, 0.0, 0.0])
    img, depth = r.render_background(T_wc)
    assert depth[120, 160] == pytest.approx(0.10, abs=1e-6)    # top face at z = 0.02
    assert img[120, 160, 2] > 150                              # ivory
    u = cam.project(np.array([[0.0115, 0.0, 0.10]]))[0]        # just outside the top face
    assert np.isinf(depth[int(round(u[1])), int(round(u[0])) + 0]) or \
        depth[int(round(u[1])), int(round(u[0]))] > 0.1


def test_shafts_drawn_above_tissue_only():
    cam = er.CameraModel(320, 240, [[250, 0, 159.5], [0, 250, 119.5], [0, 0, 1]], [0] * 5)
    surf = TissueSurface(z0=0.0, waves=())
    r = er.SceneRenderer(cam, surf, texture_size=128)
    T_wc = look_at(np.array([0.0, 0.0, 0.12]), [0.0, 0.0, 0.0])
    bg = r.render(T_wc).copy()
    above = r.render(T_wc, [(np.array([0.0, -0.03, 0.02]), np.array([0.0, 0.15, 0.3]), 0.004)]).copy()
    below = r.render(T_wc, [(np.array([0.0, -0.03, -0.02]), np.array([0.0, 0.03, -0.01]), 0.004)])
    mid = cam.project((rigid.invert(T_wc) @ np.array([0.0, -0.03, 0.02, 1.0]))[None, :3])[0]
    u, v = int(round(mid[0])), int(round(mid[1]))
    assert np.abs(above[v, u].astype(int) - bg[v, u]).sum() > 30
    assert np.array_equal(below, bg)


def test_load_boxes(tmp_path):
    p = tmp_path / 'v.txt'
    lines = ['# two boxes, mm', '2'] + ['%d %d %d' % (x, y, z) for _ in range(2)
                                       for x in (0, 10) for y in (0, 20) for z in (0, 30)]
    p.write_text('\n'.join(lines) + '\n')
    boxes = er.load_boxes(str(p), scaling=0.001)
    assert len(boxes) == 2 and boxes[0][-1].tolist() == [0.01, 0.02, 0.03]
    c, axes, half = er.box_from_vertices(boxes[0])
    np.testing.assert_allclose(sorted(half), [0.005, 0.01, 0.015])
    p.write_text('2\n1 2 3\n')
    with pytest.raises(ValueError, match='expected 2 boxes'):
        er.load_boxes(str(p))
    p.write_text('1\n' + 'a b c\n' * 8)
    with pytest.raises(ValueError, match='not numeric'):
        er.load_boxes(str(p))


def slab_depth(cam, T_wc, centre, axes, half):
    """Independent reference: per-pixel ray/oriented-box slab test (optical depth, inf = miss)."""
    rays = cam.pixel_rays().reshape(-1, 3).astype(np.float64)
    d = rays @ T_wc[:3, :3].T @ axes.T
    o = axes @ (T_wc[:3, 3] - centre)
    with np.errstate(divide='ignore', invalid='ignore'):
        ta, tb = (-half - o) / d, (half - o) / d
    tn = np.nan_to_num(np.minimum(ta, tb), nan=-np.inf).max(axis=1)
    tf = np.nan_to_num(np.maximum(ta, tb), nan=np.inf).min(axis=1)
    return np.where((tn <= tf) & (tn > 0), tn, np.inf).reshape(cam.height, cam.width)


@pytest.mark.parametrize('eye_pos', [(0.0, 0.0, 0.12), (0.05, 0.0, 0.012), (0.0, 0.0, 0.05)])
def test_boxes_match_slab_reference_also_when_clipped(eye_pos):
    """Boxes partly outside the view and straddling the camera plane render like a slab test."""
    cam = er.CameraModel(320, 240, [[200, 0, 159.5], [0, 200, 119.5], [0, 0, 1]],
                         [-0.12, 0.05, 0.0005, -0.0003, 0.0])
    boxes = [np.array([[x, y, z] for x in (-0.01, 0.01) for y in (-0.01, 0.01) for z in (0.0, 0.02)]),
             np.array([[x, y, z] for x in (0.02, 0.2) for y in (-0.2, 0.2) for z in (-0.01, 0.03)])]
    boxes[1] = boxes[1] @ rigid.rot_z(0.3).T
    r = er.SceneRenderer(cam, TissueSurface(z0=-1.0, waves=()), boxes=boxes, texture_size=128)
    T_wc = look_at(np.array(eye_pos), [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    _, depth = r.render_background(T_wc)
    ref = np.full_like(depth, np.inf, dtype=np.float64)
    for b in boxes:
        ref = np.minimum(ref, slab_depth(cam, T_wc, *er.box_from_vertices(b)))
    hit_r, hit = np.isfinite(ref), depth < 0.5   # the tissue plane far below is at >= 1 m
    assert hit_r.sum() > 1000
    # interior pixels (3x3 neighbourhood agrees in the reference) must agree exactly
    k = np.ones((3, 3), np.uint8)
    inner = cv2.erode(hit_r.astype(np.uint8), k).astype(bool)
    outer = ~cv2.dilate(hit_r.astype(np.uint8), k).astype(bool)
    assert np.all(hit[inner]) and not np.any(hit[outer])
    # away from occlusion boundaries (depth jumps between boxes) the depth is the slab depth
    rf = np.where(hit_r, ref, 10.0).astype(np.float32)
    smooth = (cv2.dilate(rf, k) - cv2.erode(rf, k)) < 0.004
    both = inner & smooth
    assert both.sum() > 0.9 * inner.sum()
    np.testing.assert_allclose(depth[both], ref[both], rtol=1e-4, atol=1e-6)


def test_polygon_clipping():
    sq = np.array([[-2.0, -2.0], [2.0, -2.0], [2.0, 2.0], [-2.0, 2.0]])
    c = er.clip_polygon(sq, 1.0, 0.5)
    assert c[:, 0].min() == -1.0 and c[:, 0].max() == 1.0 and np.abs(c[:, 1]).max() == 0.5
    assert len(er.clip_polygon(sq + 10.0, 1.0, 1.0)) == 0
    tri = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 1.0], [1.0, 0.0, 1.0]])
    c3 = er.clip_polygon_near(tri, 0.5)
    assert len(c3) == 4 and c3[:, 2].min() == pytest.approx(0.5)


def test_distort_matches_opencv_projection():
    """The vectorised distortion used for outlines equals cv2.projectPoints (plumb_bob and
    rational_polynomial), including points outside the field of view."""
    rng = np.random.default_rng(3)
    xy = rng.uniform(-0.9, 0.9, (200, 2))
    for D, model in (([-0.12, 0.05, 0.0005, -0.0003, 0.01], 'plumb_bob'),
                     ([0.1, -0.05, 0.001, 0.0007, 0.002, 0.05, -0.01, 0.003], 'rational_polynomial')):
        cam = er.CameraModel(640, 480, [[500, 0, 319.5], [0, 510, 239.5], [0, 0, 1]], D,
                             distortion_model=model)
        ref, _ = cv2.projectPoints(np.column_stack([xy, np.ones(len(xy))]).reshape(-1, 1, 3),
                                   np.zeros(3), np.zeros(3), cam.K, cam.D)
        np.testing.assert_allclose(cam.distort(xy), ref.reshape(-1, 2), atol=1e-9)


@pytest.mark.parametrize('q', [(0.0, 0.0, 0.09, 0.0), (0.2, -0.2, 0.05, 0.3), (-0.3, 0.2, 0.12, -0.3)])
@pytest.mark.parametrize('size', [(1280, 720), (1920, 1080)])
def test_tissue_depth_truth_at_720p_and_1080p_moving_camera(cams, q, size):
    """Coarse-to-fine tissue solve (the moving-camera path) at the shipped camera (1280x720, and
    scaled to 1920x1080: coarser grid steps 6/3 px) from ECM-like viewpoints: back-projected
    pixels lie on the analytic surface (texture area)."""
    surf = TissueSurface(z0=0.07)
    cam = cams['left'].scaled(*size)
    r = er.SceneRenderer(cam, surf)
    assert r.rays_c is not None        # the coarse grid is in use at this size
    assert r.colour_step == er.tissue_grid_steps(size[0])[1] == size[0] // 640
    eye = np.array([0.14, 0.0, 0.24]) + np.array([-0.13 + q[0] * 0.1, q[1] * 0.1, -0.17]) * 0.55
    T_wc = look_at(eye, [0.0 + q[3] * 0.05, q[2] - 0.09, 0.07])
    _, depth = r.render_background(T_wc)
    img2, none = r.render_background(T_wc, with_depth=False)
    assert none is None and np.array_equal(img2, _)   # same image without the depth buffer
    rays = cam.pixel_rays()
    v, u = np.mgrid[4:size[1] - 4:11 * size[1] // 720, 4:size[0] - 4:13 * size[0] // 1280]
    p = (rays[v, u] * depth[v, u][..., None]).reshape(-1, 3)
    ok = np.all(np.isfinite(p), axis=1)
    p = p[ok] @ T_wc[:3, :3].T + T_wc[:3, 3]
    inside = (np.abs(p[:, 0]) < 0.14) & (np.abs(p[:, 1]) < 0.14)
    assert inside.sum() > 2000
    err = np.abs(p[inside, 2] - surf.height(p[inside, 0], p[inside, 1]))
    # 0.15 mm (the single-grid solve of the previous release reached 0.47 mm at q[1])
    assert err.max() < 1.5e-4, err.max()


@pytest.mark.parametrize('size', [(1280, 720), (1920, 1080)])
def test_box_partly_buried_in_tissue_same_without_depth_buffer(cams, size):
    """A bone box half under the tissue: the z-test against the tissue (upsampled only where the
    box is when no depth buffer is wanted) hides the buried part, identically in both paths, and
    the visible box pixels have the slab-test depth of the box."""
    cam = cams['left'].scaled(*size)
    surf = TissueSurface(z0=0.07)
    box = np.array([[x, y, z] for x in (-0.02, 0.02) for y in (-0.015, 0.015) for z in (0.055, 0.075)])
    r = er.SceneRenderer(cam, surf, boxes=[box])
    T_wc = look_at(np.array([0.06, 0.0, 0.20]), [0.0, 0.0, 0.07])
    img, depth = r.render_background(T_wc)
    img2, none = r.render_background(T_wc, with_depth=False)
    assert none is None and np.array_equal(img, img2)
    slab = slab_depth(cam, T_wc, *er.box_from_vertices(box))
    inside = np.isfinite(slab)
    k = np.ones((5, 5), np.uint8)
    inner = cv2.erode(inside.astype(np.uint8), k).astype(bool)
    shows_box = inner & (np.abs(depth - slab) < 1e-4 * slab)
    rays = cam.pixel_rays()
    p = rays * depth[..., None]
    p = p.reshape(-1, 3) @ T_wc[:3, :3].T + T_wc[:3, 3]
    on_tissue = (np.abs(p[:, 2] - surf.height(p[:, 0], p[:, 1])) < 3e-4).reshape(depth.shape)
    # both the box and the tissue covering its buried part are seen inside its silhouette
    assert shows_box.sum() > 0.1 * inner.sum() and (inner & on_tissue).sum() > 0.1 * inner.sum()
    # where the box is drawn it is in front of the tissue hit by the same ray (as the z-test says)
    tissue_only = er.SceneRenderer(cam, surf)
    _, dt = tissue_only.render_background(T_wc)
    assert np.all(slab[shows_box] <= dt[shows_box] * (1 + 1e-4))
    assert np.all(depth[inner] <= slab[inner] * (1 + 1e-4))
