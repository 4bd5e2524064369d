"""Cross-sections of a tape: the shape of the section across the width, and its flattening.

A section is described by its width (arc length across, b) and its shape: the centre line of
the section as a plane curve (y(s), z(s)) of the arc length s in [-b/2, b/2], through the
origin at s = 0 with tangent +y there, and its unit normal. Flattening the section by a
fraction f scales its curvature by (1 - f) with the centre point and its tangent held, so that
f = 1 is the flat strip of the same width. The circular arc of the benchmark tape is the one
section today; a lenticular or a laminated section implements the same two methods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CircularArcSection:
    """A circular-arc section of radius R [m] and angle alpha [rad], centre of curvature on +z."""

    R: float
    alpha: float

    @classmethod
    def from_tape(cls, tape) -> CircularArcSection:
        """The section of a :class:`tapecoil.config.TapeConfig`."""
        return cls(R=tape.R, alpha=tape.alpha)

    @property
    def width(self) -> float:
        """Arc width b = R alpha [m]."""
        return self.R * self.alpha

    @property
    def chord(self) -> float:
        """Projected width 2 R sin(alpha / 2) [m]."""
        return 2 * self.R * math.sin(self.alpha / 2)

    def curvature(self, s: np.ndarray) -> np.ndarray:
        """Transverse curvature [1/m] at arc lengths s (positive: centre of curvature on +z)."""
        return np.full_like(np.asarray(s, dtype=float), 1.0 / self.R)

    def shape(self, s: np.ndarray, flattening: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y, z, normal) of the section flattened by ``flattening`` at arc lengths s.

        y, z [m] have the shape of s; the normal (2, n) holds the (y, z) components of the unit
        normal on the +z side at s = 0. Closed forms of the arc of curvature (1 - f)/R, regular
        as the curvature vanishes.
        """
        s = np.asarray(s, dtype=float)
        ks = (1.0 - flattening) / self.R * s
        # sin(ks)/kappa and (1 - cos(ks))/kappa, written to stay regular as kappa -> 0
        y = s * np.sinc(ks / np.pi)
        z = s * np.sin(ks / 2) * np.sinc(ks / (2 * np.pi))
        return y, z, np.vstack([-np.sin(ks), np.cos(ks)])
