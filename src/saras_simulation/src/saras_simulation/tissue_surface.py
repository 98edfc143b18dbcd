"""Synthetic tissue surface of the simulated surgical site (shared by the endoscope renderer and
the contact source). ROS-agnostic.

The surface is a height field in the ``world`` frame (z up):
``z = z0 + sum_i a_i * sin(kx_i * (x - cx) + ky_i * (y - cy) + phi_i)``, metres. Tissue lies
below the surface; the outward normal points up-ish (+z component > 0).
"""
import math

import numpy as np

#: Default undulations: (amplitude [m], kx [rad/m], ky [rad/m], phase [rad]).
DEFAULT_WAVES = ((0.004, 40.0, 15.0, 0.3), (0.002, -25.0, 55.0, 1.1), (0.001, 110.0, 90.0, 2.0))


class TissueSurface(object):
    """Height-field tissue surface; all methods accept numpy arrays (vectorised)."""

    def __init__(self, z0=0.07, centre=(0.0, 0.0), waves=DEFAULT_WAVES):
        self.z0 = float(z0)
        self.cx, self.cy = float(centre[0]), float(centre[1])
        w = np.asarray(waves, dtype=float).reshape(-1, 4)
        if not np.all(np.isfinite(w)) or not np.isfinite(self.z0):
            raise ValueError('tissue surface parameters must be finite')
        self.a, self.kx, self.ky, self.phi = w[:, 0], w[:, 1], w[:, 2], w[:, 3]
        self._waves = tuple(tuple(float(v) for v in row) for row in w)
        # Bound of |grad h| (used by the ray caster to pick the iteration count).
        self.max_slope = float(np.sum(np.abs(self.a) * np.hypot(self.kx, self.ky)))

    @classmethod
    def from_config(cls, cfg):
        """From a dict ``{z0: m, centre: [x, y], waves: [[a, kx, ky, phi], ...]}``."""
        cfg = cfg or {}
        try:
            return cls(cfg.get('z0', 0.07), cfg.get('centre', (0.0, 0.0)),
                       cfg.get('waves', DEFAULT_WAVES))
        except (TypeError, ValueError) as ex:
            raise ValueError('parameter tissue invalid: %s' % ex)

    def height(self, x, y):
        """Surface height z [m] at world (x, y) [m]."""
        x = np.asarray(x, dtype=float)[..., None] - self.cx
        y = np.asarray(y, dtype=float)[..., None] - self.cy
        return self.z0 + np.sum(self.a * np.sin(self.kx * x + self.ky * y + self.phi), axis=-1)

    def gradient(self, x, y):
        """(dz/dx, dz/dy) at world (x, y)."""
        x = np.asarray(x, dtype=float)[..., None] - self.cx
        y = np.asarray(y, dtype=float)[..., None] - self.cy
        c = self.a * np.cos(self.kx * x + self.ky * y + self.phi)
        return np.sum(c * self.kx, axis=-1), np.sum(c * self.ky, axis=-1)

    def normal(self, x, y):
        """Unit outward normal (..., 3) at world (x, y)."""
        gx, gy = self.gradient(x, y)
        n = np.stack([-gx, -gy, np.ones_like(gx)], axis=-1)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def _height_gradient(self, x, y):
        """Height z [m] and gradient (dz/dx, dz/dy) at one world point (x, y), plain floats: the
        same sums as :meth:`height` and :meth:`gradient` without numpy's per-call cost on 3 waves."""
        x, y = x - self.cx, y - self.cy
        h = gx = gy = 0.0
        for a, kx, ky, phi in self._waves:
            arg = kx * x + ky * y + phi
            h += a * math.sin(arg)
            c = a * math.cos(arg)
            gx += c * kx
            gy += c * ky
        return self.z0 + h, gx, gy

    def closest_point(self, p, iterations=8):
        """Closest surface point to ``p`` (3,) [m] by iterated tangent-plane projection.

        Returns (point (3,), unit outward normal (3,), signed distance [m], > 0 above the surface).
        """
        px, py, pz = (float(v) for v in p)
        x, y = px, py
        for it in range(iterations + 1):
            h, gx, gy = self._height_gradient(x, y)
            norm = math.sqrt(gx * gx + gy * gy + 1.0)
            nx, ny, nz = -gx / norm, -gy / norm, 1.0 / norm
            d = (px - x) * nx + (py - y) * ny + (pz - h) * nz     # signed distance to the tangent plane
            if it == iterations:
                return np.array([x, y, h]), np.array([nx, ny, nz]), float(d)
            x, y = px - d * nx, py - d * ny
