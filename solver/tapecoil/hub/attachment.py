"""The tape's root attached to the hub: flattened onto it, then turned with it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapecoil.core.rotation import rotation_matrix
from tapecoil.models.edges import edge_conditions
from tapecoil.models.shell import NaghdiShell


@dataclass
class HubRoot:
    """The root edge of a tape attached to the hub: flattened onto it, then turned with it.

    ``set(flattening, hub_angle)``: with flattening f in [0, 1] the root section is the arc of
    the same length with curvature (1 - f)/R (f = 0 the tape's own section, f = 1 flat on the
    hub's top generator), keeping its centre line in place; the section is then turned by
    ``hub_angle`` [rad] about the hub axis (along y through ``axis_point``) in the coiling sense:
    the root moves from the top of the hub towards -x and the tape wraps behind it. Displacement
    and director are both prescribed (rigid attachment).
    """

    model: NaghdiShell
    tag: int
    axis_point: np.ndarray
    R: float

    def __post_init__(self):
        self.values, self.bcs = edge_conditions(self.model, self.tag)
        self.flattening = 0.0
        self.angle = 0.0

    def section(self, xi: np.ndarray, flattening: float) -> tuple[np.ndarray, np.ndarray]:
        """Positions and directors (3, n) of the root section at flattening f, before turning."""
        s = xi[1]
        kappa = (1.0 - flattening) / self.R
        ks = kappa * s
        # sin(ks)/kappa and (1 - cos(ks))/kappa, regular as kappa -> 0
        y = s * np.sinc(ks / np.pi)
        z = s * np.sin(ks / 2) * np.sinc(ks / (2 * np.pi))
        x = xi[0].copy()
        d = np.vstack([np.zeros_like(s), -np.sin(ks), np.cos(ks)])
        return np.vstack([x, y, z]), d

    def set(self, flattening: float, hub_angle: float) -> None:
        geom = self.model.strip.geometry
        Q = rotation_matrix(np.array([0.0, -1.0, 0.0]), hub_angle)
        c = np.asarray(self.axis_point, dtype=float).reshape(3, 1)

        def displacement(x):
            X, _ = self.section(x, flattening)
            return Q @ (X - c) + c - geom.phi0(x)

        def angles(x):
            _, d = self.section(x, flattening)
            # the director turns about -y: theta_1 (about +y) goes to -hub_angle
            return self.model.angles_of(Q @ d, x, rotation_near=-hub_angle)

        self.values[0].interpolate(displacement)
        self.values[1].interpolate(angles)
        self.flattening = flattening
        self.angle = hub_angle
