"""The tape's root attached to the hub: flattened onto it, then turned with it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tapecoil.hub.frame import HubFrame
from tapecoil.models.edges import edge_conditions
from tapecoil.models.shell import NaghdiShell


@dataclass
class HubRoot:
    """The root edge of a tape attached to the hub: flattened onto it, then turned with it.

    ``set(flattening, hub_angle)``: with flattening f in [0, 1] the root section is the
    ``section`` flattened by f (f = 0 the tape's own section, f = 1 flat on the hub's generator
    the root touches), keeping its centre line in place; the section is then turned by
    ``hub_angle`` [rad] with the hub (:class:`~tapecoil.hub.frame.HubFrame`): the root moves
    from that generator towards -x and the tape wraps behind it. Displacement and director are
    both prescribed (rigid attachment).
    """

    model: NaghdiShell
    tag: int
    frame: HubFrame
    section: object  # a section of tapecoil.geometry.sections

    def __post_init__(self):
        self.values, self.bcs = edge_conditions(self.model, self.tag)
        self.flattening = 0.0
        self.angle = 0.0

    def section_at(self, xi: np.ndarray, flattening: float) -> tuple[np.ndarray, np.ndarray]:
        """Positions and directors (3, n) of the root section at flattening f, before turning."""
        y, z, normal = self.section.shape(xi[1], flattening)
        x = xi[0].copy()
        d = np.vstack([np.zeros_like(y), normal[0], normal[1]])
        return np.vstack([x, y, z]), d

    def set(self, flattening: float, hub_angle: float) -> None:
        geom = self.model.strip.geometry
        Q = self.frame.rotation(hub_angle)

        def displacement(x):
            X, _ = self.section_at(x, flattening)
            return self.frame.turn_points(X, hub_angle) - geom.phi0(x)

        def angles(x):
            _, d = self.section_at(x, flattening)
            near = self.frame.director_angle_change(hub_angle)
            return self.model.angles_of(Q @ d, x, rotation_near=near)

        self.values[0].interpolate(displacement)
        self.values[1].interpolate(angles)
        self.flattening = flattening
        self.angle = hub_angle
