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
from collections.abc import Callable
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from tapecoil.config import Config

# The functions a map may use, from numpy (also for complex arguments: the Jacobian is the map's
# complex-step derivative) or from UFL.
NUMPY_OPS = SimpleNamespace(sin=np.sin, cos=np.cos, sqrt=np.sqrt, exp=np.exp, log=np.log)


def _ufl_ops():
    import ufl

    return SimpleNamespace(sin=ufl.sin, cos=ufl.cos, sqrt=ufl.sqrt, exp=ufl.exp, log=ufl.ln)


class Surface:
    """A shell mid-surface given by an exact map phi0 from a rectangle of parameters.

    The parameter rectangle is [0, length] x [-width/2, width/2] for strips and a geometry's own
    ranges otherwise (``xi_range``). A subclass writes the map once, in :meth:`map`, with the
    functions of ``ops`` (sin, cos, sqrt, exp, log); the numpy map, the UFL map of the shell's
    forms and the Jacobian (the complex-step derivative of the numpy map, exact to round-off)
    all follow from it, so they cannot disagree. Edge tags (:mod:`tapecoil.geometry.meshes`):
    XI1_MIN, XI1_MAX, XI2_MIN and XI2_MAX, the parameter bound each edge lies on, named so in
    the mesh's physical groups ("xi1_min" ...); a tape's strip names them by what they are on
    the tape ("root", "free_end", "side_neg", "side_pos").
    """

    xi_range: tuple[tuple[float, float], tuple[float, float]]

    def map(self, xi, ops) -> tuple:
        """The three coordinates of phi0 at parameters (xi[0], xi[1]), written with ``ops``."""
        raise NotImplementedError

    def _evaluate(self, xi, ops, on: str) -> tuple:
        """The map's three coordinates at ``xi`` with ``ops``; a map written with math's or
        numpy's functions instead of ``ops``'s fails here with the way out said."""
        try:
            return tuple(self.map(xi, ops))
        except (TypeError, AttributeError) as exc:
            raise TypeError(
                f"the map of {type(self).__name__} cannot be evaluated on {on} ({exc}). Write it with "
                "the functions of its ops argument (ops.sin, ops.cos, ops.sqrt, ops.exp, ops.log), "
                "not math's or numpy's: the same map is evaluated on arrays of parameters, on complex "
                "ones for its Jacobian and on UFL expressions for the shell's forms, and ops holds the "
                "functions for each"
            ) from exc

    def phi0(self, xi: np.ndarray) -> np.ndarray:
        """3D mid-surface points (3, n) of parameter points xi (2, n) or (3, n)."""
        xi = np.asarray(xi)
        return np.vstack(np.broadcast_arrays(*self._evaluate(xi, NUMPY_OPS, "arrays of parameters")))

    def phi0_ufl(self, xi):
        """The map phi0 as a UFL vector of the parameter coordinates (SpatialCoordinate)."""
        import ufl

        return ufl.as_vector(list(self._evaluate(xi, _ufl_ops(), "UFL expressions (the shell's forms)")))

    def jacobian(self, xi: np.ndarray) -> np.ndarray:
        """d phi0 / d xi at parameter points: shape (3, 2, n) (complex-step derivative)."""
        xi = np.asarray(xi, dtype=float)[:2]
        step = 1e-30 * np.maximum(1.0, np.abs(xi).max(axis=1, keepdims=True))
        J = np.empty((3, 2, xi.shape[1]))
        for k in range(2):
            shifted = xi.astype(complex)
            shifted[k] += 1j * step[k]
            phi = self._evaluate(shifted, NUMPY_OPS, "complex parameters (its Jacobian by complex step)")
            J[:, k] = np.vstack(np.broadcast_arrays(*phi)).imag / step[k]
        return J

    def frame(self, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Orthonormal frame (t1, t2, n0), each (3, n), as the shell module builds it in UFL."""
        J = self.jacobian(xi)
        n0 = np.cross(J[:, 0].T, J[:, 1].T).T
        n0 /= np.linalg.norm(n0, axis=0)
        t1 = J[:, 0] / np.linalg.norm(J[:, 0], axis=0)
        t2 = np.cross(n0.T, t1.T).T
        return t1, t2, n0

    def check(self, samples: int = 7, tolerance: float = 1e-6) -> float:
        """Check the surface over its closed parameter rectangle; the largest discrepancy found.

        Sampled on a ``samples`` x ``samples`` grid that includes the rectangle's edges and
        corners: the Jacobian against finite differences of phi0 (central inside, one-sided on
        the edges, so that the map is not evaluated outside its rectangle; relative to the
        Jacobian's size), and a regular map: a non-zero area element |d phi0/d xi_1 x d phi0/d
        xi_2| everywhere. Raises ValueError beyond ``tolerance`` (a map that is not smooth where
        it is sampled) and where the area element vanishes (tangents parallel or of zero
        length: a fold, or a pole such as a sphere's, where no shell can be formulated), naming
        the parameter points and the edges they lie on.
        """
        if samples < 2:
            raise ValueError(f"check: samples = {samples} must be at least 2 (the rectangle's edges)")
        (a0, a1), (b0, b1) = self.xi_range
        g = np.linspace(0.0, 1.0, samples)
        xi = np.vstack([np.repeat(a0 + g * (a1 - a0), samples), np.tile(b0 + g * (b1 - b0), samples)])
        J = self.jacobian(xi)
        scale = np.abs(J).max()
        worst = 0.0
        for k, (lo, hi) in enumerate(self.xi_range):
            h = 1e-6 * (hi - lo)
            e = np.zeros((2, 1))
            e[k] = h
            low, high = (np.isclose(xi[k], bound, rtol=0, atol=h) for bound in (lo, hi))
            inside = ~(low | high)
            fd = np.empty((3, xi.shape[1]))
            p = xi[:, inside]
            fd[:, inside] = (self.phi0(p + e) - self.phi0(p - e)) / (2 * h)
            # second-order one-sided differences on the edges, from inside the rectangle
            for edge, sign in ((low, 1.0), (high, -1.0)):
                p = xi[:, edge]
                f0, f1, f2 = (self.phi0(p + sign * m * e) for m in (0, 1, 2))
                fd[:, edge] = sign * (-3 * f0 + 4 * f1 - f2) / (2 * h)
            worst = max(worst, float(np.abs(fd - J[:, k]).max() / scale))
        area = np.linalg.norm(np.cross(J[:, 0].T, J[:, 1].T), axis=1)
        if worst > tolerance:
            raise ValueError(f"the Jacobian of {type(self).__name__} disagrees with phi0 by {worst:.3g}")
        singular = area <= 1e-12 * scale**2
        if np.any(singular):
            where = [self._describe_point(point) for point in xi[:, singular].T]
            shown = "; ".join(where[:4]) + (f"; and {len(where) - 4} more" if len(where) > 4 else "")
            raise ValueError(
                f"{type(self).__name__} is singular (zero area element: the tangents d phi0/d xi_1 and "
                f"d phi0/d xi_2 are parallel or vanish) at xi = {shown}. No shell can be formulated "
                "there: a map that folds, or a pole such as a sphere's, which must be left out of the "
                "parameter rectangle (e.g. a small hole about it)"
            )
        return worst

    def _describe_point(self, point) -> str:
        """A parameter point and the edges of the rectangle it lies on."""
        names = []
        for k, (lo, hi) in enumerate(self.xi_range):
            tol = 1e-9 * (hi - lo)
            if abs(point[k] - lo) <= tol:
                names.append(f"xi{k + 1}_min")
            elif abs(point[k] - hi) <= tol:
                names.append(f"xi{k + 1}_max")
        text = f"({point[0]:.6g}, {point[1]:.6g})"
        if len(names) == 2:
            return f"{text} (the corner of {names[0]} and {names[1]})"
        if names:
            return f"{text} (on the edge {names[0]})"
        return f"{text} (inside)"


@dataclass(frozen=True)
class MappedSurface(Surface):
    """A surface stated by its map: ``function(xi, ops)`` gives (x, y, z) over ``xi_range``.

    For a benchmark or a new shape, e.g. a quarter of a cylinder of radius 2 and length 3::

        MappedSurface(lambda xi, ops: (2 * ops.cos(xi[1]), xi[0], 2 * ops.sin(xi[1])),
                      ((0.0, 3.0), (0.0, math.pi / 2)))

    Call :meth:`Surface.check` once to see that the map is smooth and regular.
    """

    function: Callable
    xi_range: tuple[tuple[float, float], tuple[float, float]]

    def map(self, xi, ops) -> tuple:
        return tuple(self.function(xi, ops))


@dataclass(frozen=True)
class StripGeometry(Surface):
    """A cylindrical strip: arc radius R [m] (inf: flat), arc width b [m], length L [m], from
    ``start`` [m] along the tape (a piece of a longer tape, as a hybrid's shell window is)."""

    R: float
    width: float
    length: float
    start: float = 0.0

    @classmethod
    def from_config(cls, config: Config) -> StripGeometry:
        return cls(R=config.tape.R, width=config.tape.b, length=config.tape.L)

    @property
    def xi_range(self):
        return ((self.start, self.start + self.length), (-self.width / 2, self.width / 2))

    @property
    def flat(self) -> bool:
        return math.isinf(self.R)

    def map(self, xi, ops) -> tuple:
        x, s = xi[0], xi[1]
        if self.flat:
            return x, s, 0 * x
        return x, self.R * ops.sin(s / self.R), self.R * (1 - ops.cos(s / self.R))

    def phi0_inverse(self, X: np.ndarray) -> np.ndarray:
        """Parameter points (2, n) of 3D mid-surface points X (3, n); inverse of :meth:`phi0`."""
        if self.flat:
            return np.vstack([X[0], X[1]])
        return np.vstack([X[0], self.R * np.arctan2(X[1], self.R - X[2])])


@dataclass(frozen=True)
class AnnulusGeometry(Surface):
    """A flat annulus R_inner <= r <= R_outer in the x-y plane, slit along the +x axis.

    Parameters: xi_1 = polar angle (0 to 2 pi, the slit's two edges are "xi1_min" and "xi1_max"),
    xi_2 = radius ("xi2_min" the inner, "xi2_max" the outer edge).
    """

    R_inner: float
    R_outer: float

    @property
    def xi_range(self):
        return ((0.0, 2 * math.pi), (self.R_inner, self.R_outer))

    def map(self, xi, ops) -> tuple:
        a, r = xi[0], xi[1]
        return r * ops.cos(a), r * ops.sin(a), 0 * a
