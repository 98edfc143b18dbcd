"""Simulated vision-based contact estimator (D7.2 Section 8), ROS-agnostic core of contact_sim.

For a tool tip position in ``world`` the model returns the penetration depth of the tip into
the tissue surface (:class:`saras_simulation.tissue_surface.TissueSurface`) and the contact
direction: the unit surface normal at the closest surface point, pointing out of the tissue,
expressed in the tool's base frame (``mesa_<side>/sbs_world``). Out of contact the depth is 0
and the direction is still the outward normal below the tip, so the published force
``depth * K * direction / |direction|`` of saras contact_forces is exactly zero.
"""
import math

import numpy as np


class ContactEstimate(object):
    """depth [m] (>= 0), direction (3,) unit vector in the base frame, in_contact flag; tip (3,) [m]
    in world and its exact signed distance [m] to the surface (> 0 above)."""
    __slots__ = ('depth', 'direction', 'in_contact', 'tip', 'signed_distance')

    def __init__(self, depth, direction, in_contact, tip=None, signed_distance=float('nan')):
        self.depth = depth
        self.direction = direction
        self.in_contact = in_contact
        self.tip = tip
        self.signed_distance = signed_distance


class ContactModel(object):
    """Tip-versus-tissue penetration with an optional estimator noise and depth saturation.

    ``max_depth`` [m] clips the reported depth (a vision estimator cannot see deeper);
    ``noise_std`` [m] adds Gaussian noise to the depth while in contact (0 = exact).
    """

    def __init__(self, surface, max_depth=0.03, noise_std=0.0, seed=0):
        if not (max_depth > 0 and noise_std >= 0):
            raise ValueError('contact: max_depth must be > 0 and noise_std >= 0')
        self.surface = surface
        self.max_depth = float(max_depth)
        self.noise_std = float(noise_std)
        self._rng = np.random.default_rng(seed)

    def estimate(self, tip_world, R_base_world):
        """Contact for a tip at ``tip_world`` (3,) [m]; ``R_base_world`` rotates world -> base.

        Raises ValueError for non-finite input (the node then reports and publishes nothing new).
        """
        tip = np.asarray(tip_world, dtype=float)
        R = np.asarray(R_base_world, dtype=float)
        if tip.shape != (3,) or not np.all(np.isfinite(tip)) or not np.all(np.isfinite(R)):
            raise ValueError('non-finite tool tip position or frame rotation')
        _, n, sd = self.surface.closest_point(tip)
        depth = max(0.0, -sd)
        in_contact = depth > 0.0
        if in_contact and self.noise_std > 0:
            depth = max(0.0, depth + float(self._rng.normal(0.0, self.noise_std)))
        depth = min(depth, self.max_depth)
        d = R @ n
        d /= np.linalg.norm(d)
        if not (math.isfinite(depth) and np.all(np.isfinite(d))):
            raise ValueError('contact estimate is not finite')
        return ContactEstimate(depth, d, in_contact, tip, float(sd))
