"""Closest points on a surface of biquadratic (9-node) quadrilaterals, and a buffered search.

Geometry only, no mechanics: a surface is given by node positions (N, 3) and cells (Nc, 9) of
node indices in the node order of basix's degree-2 Lagrange quadrilateral (the order of
DOLFINx's Q2 dofmaps). :func:`closest_points` projects points onto given cells;
:class:`CandidateSearch` finds, for query nodes, the cells that can come within a distance of
them, and keeps that list while nothing has moved more than half its buffer (a Verlet list:
two points that each moved less than half the buffer have closed in by less than the buffer, so
a pair now within ``reach`` was within ``reach + buffer`` at the search).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

# tensor indices (i, j) of the nodes of basix's Q2 quadrilateral: its element.points times 2
Q2_TENSOR = np.array([[0, 0], [2, 0], [0, 2], [2, 2], [1, 0], [0, 1], [2, 1], [1, 2], [1, 1]])


def _lagrange2(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic Lagrange basis on [0, 1] (nodes 0, 1/2, 1) and its derivative, (3, n) each."""
    values = np.stack([2 * (t - 0.5) * (t - 1), -4 * t * (t - 1), 2 * t * (t - 0.5)])
    derivatives = np.stack([4 * t - 3, 4 - 8 * t, 4 * t - 1])
    return values, derivatives


def q2_basis(ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Q2 shape functions N (n, 9) and their reference gradients (n, 9, 2) at points ref (n, 2)."""
    lx, dx = _lagrange2(ref[:, 0])
    ly, dy = _lagrange2(ref[:, 1])
    i, j = Q2_TENSOR.T
    N = (lx[i] * ly[j]).T
    dN = np.stack([(dx[i] * ly[j]).T, (lx[i] * dy[j]).T], axis=-1)
    return N, dN


def closest_points(
    points: np.ndarray, cells_xyz: np.ndarray, iterations: int = 8, start: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """The point of each cell closest to each point: ``points`` (n, 3), ``cells_xyz`` (n, 9, 3).

    Gauss-Newton on |x - y(r)|^2 over the reference square: a coordinate on an edge that the
    descent would carry out of the square is held there and the other is solved for alone, so
    that a point beyond an edge projects onto the edge's closest point (a clipped full step
    would stop beside it). The neglected term of Newton is the distance times the surface's
    curvature, so for points within a few thicknesses of a shell whose radius of curvature is
    many thicknesses the iteration contracts by that ratio each step.

    Returns ``ref`` (n, 2), ``held`` (n, 2) the coordinates held on an edge, the closest point
    ``y`` (n, 3), the shape functions ``N`` (n, 9) there, the unit ``normal`` (n, 3) of the
    cell's orientation (dy/dr_1 x dy/dr_2), the ``distance`` (n,) and the unit ``direction``
    (n, 3) from y to the point. ``start``: reference coordinates to start from (a previous
    projection), else the cell centres. Computed by the compiled kernel
    (:func:`tapecoil.contact.kernels.closest_points`, which takes the points and cells by index).
    """
    from tapecoil.contact import kernels

    n = points.shape[0]
    x = np.concatenate([np.asarray(points, dtype=float).reshape(n, 3), np.asarray(cells_xyz).reshape(-1, 3)])
    cells = n + np.arange(9 * n, dtype=np.int64).reshape(n, 9)
    index = np.arange(n, dtype=np.int64)
    return kernels.closest_points(index, index, x, cells, start=start, iterations=iterations)


def box_distance(points: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Distance of points (n, d) from axis-aligned boxes [lower, upper] (n, d), 0 inside."""
    return np.linalg.norm(np.maximum(np.maximum(lower - points, points - upper), 0.0), axis=1)


class CandidateSearch:
    """Candidate (query node, cell) pairs of a surface that may come within ``reach`` of each other.

    ``cells`` (Nc, 9) node indices; ``material`` (N, 2) the nodes' reference (material)
    coordinates and ``exclusion`` a distance in them: a cell closer than that to a query node in
    the reference configuration is the node's own neighbourhood, never its partner. ``buffer``:
    the Verlet buffer [length]; the list is rebuilt when a node has moved more than half of it.
    """

    def __init__(
        self, cells: np.ndarray, material: np.ndarray, exclusion: float, reach: float, buffer: float
    ):
        self.cells = cells
        self.reach, self.buffer, self.exclusion = reach, buffer, exclusion
        corners = material[cells]
        self.box_lower, self.box_upper = corners.min(axis=1), corners.max(axis=1)
        self.material = material
        # node -> cells, as CSR
        flat = cells.ravel()
        order = np.argsort(flat, kind="stable")
        self.node_cells = (order // cells.shape[1]).astype(np.int64)
        counts = np.bincount(flat, minlength=material.shape[0])
        self.node_cells_start = np.concatenate([[0], np.cumsum(counts)])
        self.positions_at_search: np.ndarray | None = None
        self.pairs: tuple[np.ndarray, np.ndarray] | None = None
        self.query: np.ndarray | None = None
        self.searches = 0
        # what a user of the list keeps per candidate pair (valid while ``searches`` is unchanged)
        self.data: dict = {}

    def valid_for(self, positions: np.ndarray, query: np.ndarray) -> bool:
        if self.positions_at_search is None or self.query is not query:
            return False
        moved = np.linalg.norm(positions - self.positions_at_search, axis=1)
        return float(moved.max()) <= 0.5 * self.buffer

    def candidates(self, positions: np.ndarray, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(query node, cell) candidate pairs at ``positions`` (N, 3) for the nodes ``query``."""
        if not self.valid_for(positions, query):
            self._search(positions, query)
        return self.pairs

    def _search(self, positions: np.ndarray, query: np.ndarray) -> None:
        xyz = positions[self.cells]
        # every point of a cell lies within half its longest node distance of one of its nodes
        span = np.max(np.linalg.norm(xyz[:, :, None, :] - xyz[:, None, [0, 3], :], axis=-1), axis=(1, 2))
        radius = self.reach + self.buffer + 0.5 * float(span.max(initial=0.0))
        # every node within the radius of each query node (itself included), from the tree's
        # pairs as one array: a list per node cost more than the tree's search itself
        close = cKDTree(positions).query_pairs(radius, output_type="ndarray").astype(np.int64)
        slot = np.full(len(positions), -1, dtype=np.int64)
        slot[query] = np.arange(len(query))
        which = np.concatenate([slot[close[:, 0]], slot[close[:, 1]], np.arange(len(query))])
        neighbours = np.concatenate([close[:, 1], close[:, 0], np.asarray(query, dtype=np.int64)])
        asked = which >= 0
        which, neighbours = which[asked], neighbours[asked]
        start, stop = self.node_cells_start[neighbours], self.node_cells_start[neighbours + 1]
        per = stop - start
        which = np.repeat(which, per)
        offsets = np.arange(per.sum()) - np.repeat(np.cumsum(per) - per, per)
        cell = self.node_cells[np.repeat(start, per) + offsets]
        key = np.unique(which * len(self.cells) + cell)
        which, cell = key // len(self.cells), key % len(self.cells)
        own = box_distance(self.material[query[which]], self.box_lower[cell], self.box_upper[cell])
        centre = xyz[cell, 8]
        sphere = np.max(np.linalg.norm(xyz[cell] - centre[:, None, :], axis=2), axis=1)
        clearance = np.linalg.norm(positions[query[which]] - centre, axis=1) - sphere
        keep = (own >= self.exclusion) & (clearance <= self.reach + self.buffer)
        self.pairs = (query[which[keep]], cell[keep])
        self.positions_at_search = positions.copy()
        self.query = query
        self.searches += 1
