"""Core tests of saras_simulation.contact_model and tissue_surface (no roscore)."""
import numpy as np
import pytest

from saras_common import transforms as tfm
from saras_simulation.contact_model import ContactModel
from saras_simulation.tissue_surface import TissueSurface


def brute_force_distance(surf, p, half=0.02, n=801):
    """Independent reference: min distance from p to a dense sampling of the surface."""
    xs = np.linspace(p[0] - half, p[0] + half, n)
    ys = np.linspace(p[1] - half, p[1] + half, n)
    X, Y = np.meshgrid(xs, ys)
    Z = surf.height(X, Y)
    d = np.sqrt((X - p[0]) ** 2 + (Y - p[1]) ** 2 + (Z - p[2]) ** 2)
    return d.min()


def test_flat_surface_depth_and_direction_in_base_frame():
    surf = TissueSurface(z0=0.07, waves=())
    m = ContactModel(surf)
    # mesa_left/sbs_world: yaw -90 deg about world z (world_frames.yaml) and, here, tilted 30 deg
    R_world_base = tfm.rpy_to_matrix((0.5, 0.0, -np.pi / 2))
    est = m.estimate([0.01, 0.02, 0.065], R_world_base.T)
    assert est.in_contact and est.depth == pytest.approx(0.005, abs=1e-12)
    np.testing.assert_allclose(R_world_base @ est.direction, [0, 0, 1], atol=1e-12)
    out = m.estimate([0.01, 0.02, 0.08], np.eye(3))
    assert not out.in_contact and out.depth == 0.0
    np.testing.assert_allclose(out.direction, [0, 0, 1], atol=1e-12)
    # the tip and its signed distance (the console simulator's dip servo input)
    np.testing.assert_allclose(out.tip, [0.01, 0.02, 0.08])
    assert out.signed_distance == pytest.approx(0.01) and est.signed_distance == pytest.approx(-0.005)


def test_wavy_surface_depth_matches_brute_force():
    surf = TissueSurface()
    m = ContactModel(surf)
    rng = np.random.default_rng(5)
    for _ in range(20):
        x, y = rng.uniform(-0.05, 0.05, 2)
        h = float(surf.height(x, y))
        dz = rng.uniform(-0.008, 0.008)
        p = np.array([x, y, h + dz])
        est = m.estimate(p, np.eye(3))
        ref = brute_force_distance(surf, p)
        if dz < 0:
            assert est.in_contact and est.depth == pytest.approx(ref, abs=2e-5)
        else:
            assert est.depth == 0.0
        # outward normal at the closest point: unit, up-ish, equal to the surface's own normal there
        s_pt, n_ref, _ = surf.closest_point(p)
        np.testing.assert_allclose(est.direction, n_ref, atol=1e-12)
        assert est.direction[2] > 0.8


def test_saturation_noise_and_bad_input():
    surf = TissueSurface(z0=0.0, waves=())
    m = ContactModel(surf, max_depth=0.01)
    assert m.estimate([0, 0, -0.05], np.eye(3)).depth == 0.01
    noisy = ContactModel(surf, noise_std=0.001, seed=1)
    depths = [noisy.estimate([0, 0, -0.005], np.eye(3)).depth for _ in range(2000)]
    assert np.mean(depths) == pytest.approx(0.005, abs=1e-4)
    assert np.std(depths) == pytest.approx(0.001, rel=0.1)
    with pytest.raises(ValueError):
        m.estimate([np.nan, 0, 0], np.eye(3))
    with pytest.raises(ValueError):
        m.estimate([0, 0, 0], np.full((3, 3), np.inf))
    with pytest.raises(ValueError):
        ContactModel(surf, max_depth=0)


def test_surface_config_validation():
    s = TissueSurface.from_config({'z0': 0.05, 'waves': [[0.001, 10, 0, 0]]})
    assert s.height(0.0, 0.0) == pytest.approx(0.05)
    assert s.height(np.pi / 20, 0.0) == pytest.approx(0.051)
    with pytest.raises(ValueError, match='tissue'):
        TissueSurface.from_config({'z0': 'a'})


def test_closest_point_lies_on_the_surface_along_the_normal():
    """The float closest-point iteration: the point is on the height field (numpy height), the
    normal is the numpy normal there, and the tip lies along it at the signed distance."""
    surface = TissueSurface()
    rng = np.random.default_rng(3)
    for p in rng.uniform([-0.08, -0.08, 0.05], [0.08, 0.08, 0.09], size=(200, 3)):
        s, n, sd = surface.closest_point(p)
        assert abs(s[2] - float(surface.height(s[0], s[1]))) < 1e-12
        assert np.allclose(n, surface.normal(s[0], s[1]), atol=1e-12)
        assert np.allclose(s + sd * n, p, atol=1e-4)      # tangent-plane projection (8 iterations)
