"""Where the hub is and which way it turns: the one place that knows the coiling sense.

The tape runs along +x from its root at x = 0; its section is an arc whose centre of curvature
lies on the +z side (the edges stand higher than the centre line). The hub is a rigid cylinder
of radius r_hub with its axis along the width (y), tangent to the tape's root:

- opposite sense (a tape measure): the hub lies below the tape, on the convex side of the
  section, its axis through (0, y, -(r_hub + h/2)); the tape bends towards -z, opposite in
  sense to its transverse curvature, and its section flattens onto the hub.
- equal sense: the hub lies above the tape, on the concave side, its axis through
  (0, y, +(r_hub + h/2)); the tape bends towards +z, in the sense of its transverse curvature.

In both the hub turns so that the root leaves the top (bottom) generator towards -x and the tape
wraps onto the hub from +x; the second set-up is the mirror image of the first in z = 0, the
tape's section excepted. ``s = +1`` (opposite) or ``-1`` (equal) carries that mirror through
every formula here; nothing else in the package needs to know the sense.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tapecoil.core.rotation import rotation_matrix
from tapecoil.theory.plate import SENSES


@dataclass(frozen=True)
class HubFrame:
    """The hub's axis, radius and turning sense relative to the tape's root.

    Attributes:
        radius: hub radius r_hub [m].
        thickness: tape thickness h [m] (the mid-surface lies h/2 off the hub).
        sense: "opposite" or "equal" (see the module docstring).
    """

    radius: float
    thickness: float
    sense: str = "opposite"

    def __post_init__(self):
        if self.sense not in SENSES:
            raise ValueError(f"coiling sense must be one of {SENSES}, got {self.sense!r}")

    @property
    def sign(self) -> float:
        """+1 for opposite-sense, -1 for equal-sense coiling."""
        return 1.0 if self.sense == "opposite" else -1.0

    @property
    def axis_point(self) -> np.ndarray:
        """The point of the hub axis in the plane y = 0 [m]."""
        return np.array([0.0, 0.0, -self.sign * (self.radius + self.thickness / 2)])

    @property
    def axis(self) -> np.ndarray:
        """Unit vector of the axis about which a positive hub angle turns (right hand)."""
        return np.array([0.0, -self.sign, 0.0])

    @property
    def contact_side(self) -> float:
        """Side of the mid-surface facing the hub, along the director: -1 (opposite) or +1 (equal).

        The director starts as the +z normal; the face that touches the hub and the turns
        beneath is the mid-surface plus ``contact_side * h/2`` times the director.
        """
        return -self.sign

    def rotation(self, angle: float) -> np.ndarray:
        """The rotation matrix of the hub turned by ``angle`` [rad] in the coiling sense."""
        return rotation_matrix(self.axis, angle)

    def turn_points(self, points: np.ndarray, angle: float) -> np.ndarray:
        """Points (3, n) carried round by a hub rotation of ``angle`` [rad]."""
        a = self.axis_point[:, None]
        return self.rotation(angle) @ (points - a) + a

    def director_angle_change(self, angle: float) -> float:
        """Change of the director angle theta_1 (about +y) under a hub rotation of ``angle``."""
        return -self.sign * angle

    def polar(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance from the axis [m] and swept angle [rad] of points (3, n).

        The swept angle is measured about the axis in the coiling sense from the root's place at
        hub angle 0 (the generator the tape is tangent to), in (-3 pi / 2, pi / 2]: a point the
        hub has carried round by psi sits at swept angle hub_angle - psi (mod 2 pi).
        """
        p = points - self.axis_point[:, None]
        distance = np.hypot(p[0], p[2])
        # polar angle from +x in the xz-plane, mirrored for the equal sense, from the top generator
        return distance, self.sign * np.arctan2(p[2], p[0]) - 0.5 * math.pi

    def tangent(self, angle: float) -> np.ndarray:
        """Unit tangent of the tape at the root after a hub rotation of ``angle`` (along +x at 0)."""
        return self.rotation(angle) @ np.array([1.0, 0.0, 0.0])
