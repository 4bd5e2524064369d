"""Shell mid-surfaces given by an exact map phi0 from a rectangle of parameters.

Coordinates. The tape runs along +x from its root at x = 0 to its free end at x = L; its width
runs along y. The cross-section is a circular arc of radius R and angle alpha whose centre lies
on the +z side, so the edges stand higher than the centre line (z = 0). The shell is formulated
on a flat parameter domain: xi_1 = x along the tape, xi_2 = arc length across it
(-b/2 <= xi_2 <= b/2, b = R alpha). The exact map

    phi0(xi) = (xi_1, R sin(xi_2 / R), R (1 - cos(xi_2 / R)))

takes it to the 3D mid-surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from tapecoil.config import Config

if TYPE_CHECKING:
    from tapecoil.geometry.meshes import MeshResolution


class Surface:
    """A shell mid-surface given by an exact map phi0 from a rectangle of parameters.

    The parameter rectangle is [0, length] x [-width/2, width/2] for strips and a geometry's own
    ranges otherwise (``xi_range``). Subclasses give phi0 (numpy and UFL), its Jacobian and how
    gmsh builds the mesh. Edge tags: ROOT at xi_1 = min, FREE_END at xi_1 = max, SIDE_NEG at
    xi_2 = min and SIDE_POS at xi_2 = max.
    """

    xi_range: tuple[tuple[float, float], tuple[float, float]]

    def phi0(self, xi: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def jacobian(self, xi: np.ndarray) -> np.ndarray:
        """d phi0 / d xi at parameter points: shape (3, 2, n)."""
        raise NotImplementedError

    def phi0_ufl(self, xi):
        raise NotImplementedError

    def frame(self, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Orthonormal frame (t1, t2, n0), each (3, n), as the shell module builds it in UFL."""
        J = self.jacobian(xi)
        n0 = np.cross(J[:, 0].T, J[:, 1].T).T
        n0 /= np.linalg.norm(n0, axis=0)
        t1 = J[:, 0] / np.linalg.norm(J[:, 0], axis=0)
        t2 = np.cross(n0.T, t1.T).T
        return t1, t2, n0

    def build_gmsh(self, res: MeshResolution) -> None:
        """Mesh the parameter rectangle in the current gmsh model, nodes in parameter coordinates."""
        from tapecoil.geometry.meshes import _build_parameter_rectangle

        _build_parameter_rectangle(self.xi_range, res)


@dataclass(frozen=True)
class StripGeometry(Surface):
    """A cylindrical strip: arc radius R [m] (inf: flat), arc width b [m], length L [m]."""

    R: float
    width: float
    length: float

    @classmethod
    def from_config(cls, config: Config) -> StripGeometry:
        return cls(R=config.tape.R, width=config.tape.b, length=config.tape.L)

    @property
    def xi_range(self):
        return ((0.0, self.length), (-self.width / 2, self.width / 2))

    @property
    def flat(self) -> bool:
        return math.isinf(self.R)

    def phi0(self, xi: np.ndarray) -> np.ndarray:
        """3D mid-surface points (3, n) of parameter points xi (2, n) or (3, n)."""
        x, s = xi[0], xi[1]
        if self.flat:
            return np.vstack([x, s, np.zeros_like(x)])
        return np.vstack([x, self.R * np.sin(s / self.R), self.R * (1 - np.cos(s / self.R))])

    def jacobian(self, xi: np.ndarray) -> np.ndarray:
        n = xi.shape[1]
        J = np.zeros((3, 2, n))
        J[0, 0] = 1.0
        a = np.zeros(n) if self.flat else xi[1] / self.R
        J[1, 1], J[2, 1] = np.cos(a), np.sin(a)
        return J

    def phi0_inverse(self, X: np.ndarray) -> np.ndarray:
        """Parameter points (2, n) of 3D mid-surface points X (3, n); inverse of :meth:`phi0`."""
        if self.flat:
            return np.vstack([X[0], X[1]])
        return np.vstack([X[0], self.R * np.arctan2(X[1], self.R - X[2])])

    def phi0_ufl(self, xi):
        """The map phi0 as a UFL vector of the parameter coordinates (SpatialCoordinate)."""
        import ufl

        if self.flat:
            return ufl.as_vector([xi[0], xi[1], 0.0])
        return ufl.as_vector(
            [xi[0], self.R * ufl.sin(xi[1] / self.R), self.R * (1 - ufl.cos(xi[1] / self.R))]
        )

    def build_gmsh(self, res: MeshResolution) -> None:
        """gmsh builds the 3D strip; its nodes are then moved to parameter coordinates."""
        from tapecoil.geometry.meshes import _to_parameter_coordinates, build_strip_gmsh

        build_strip_gmsh(self, res)
        _to_parameter_coordinates(self)


@dataclass(frozen=True)
class AnnulusGeometry(Surface):
    """A flat annulus R_inner <= r <= R_outer in the x-y plane, slit along the +x axis.

    Parameters: xi_1 = polar angle (0 to 2 pi, the slit's two edges are ROOT and FREE_END),
    xi_2 = radius (SIDE_NEG inner, SIDE_POS outer edge).
    """

    R_inner: float
    R_outer: float

    @property
    def xi_range(self):
        return ((0.0, 2 * math.pi), (self.R_inner, self.R_outer))

    def phi0(self, xi: np.ndarray) -> np.ndarray:
        a, r = xi[0], xi[1]
        return np.vstack([r * np.cos(a), r * np.sin(a), np.zeros_like(a)])

    def jacobian(self, xi: np.ndarray) -> np.ndarray:
        a, r = xi[0], xi[1]
        J = np.zeros((3, 2, xi.shape[1]))
        J[0, 0], J[1, 0] = -r * np.sin(a), r * np.cos(a)
        J[0, 1], J[1, 1] = np.cos(a), np.sin(a)
        return J

    def phi0_ufl(self, xi):
        import ufl

        return ufl.as_vector([xi[1] * ufl.cos(xi[0]), xi[1] * ufl.sin(xi[0]), 0.0])
