"""The geometry of the 9-node (Q2) quadrilaterals of a surface snapshot.

The connectivity read from a snapshot cells file (:func:`quad9_cells`), the cells' biquadratic
map and its Bernstein control points, where two fields on cells both vanish (:func:`crossing`),
and the material coordinate along a strip recovered from its geometry
(:func:`material_coordinate`). :mod:`tapecoil.measures.separation` measures with them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

# Lattice place (along r, along s; 0, 1, 2 for local coordinate 0, 1/2, 1) of the nodes of a VTK
# Lagrange (type 70) or biquadratic (type 28) quadrilateral, in the order the cells list them.
_I = np.array([0, 2, 2, 0, 1, 2, 1, 0, 1])
_J = np.array([0, 0, 2, 2, 0, 1, 2, 1, 1])
_QUAD9_TYPES = (28, 70)
_CORNERS = np.arange(4)
# Neighbouring nodes along the lattice lines of a cell: the edges of the graph whose path lengths
# give the arc length along the tape.
_LATTICE_EDGES = np.array(
    [(a, b) for a in range(9) for b in range(a + 1, 9) if abs(_I[a] - _I[b]) + abs(_J[a] - _J[b]) == 1]
)

# Lagrange values at the nodes 0, 1/2, 1 to Bernstein coefficients of a quadratic. The Bernstein
# form of a cell's map lies in the convex hull of its coefficients, which bounds the cell rigorously
# for the candidate search (the nodes alone do not: the surface may bulge beyond them).
_TO_BERNSTEIN = np.array([[1.0, 0.0, 0.0], [-0.5, 2.0, -0.5], [0.0, 0.0, 1.0]])
BERNSTEIN_9 = np.kron(_TO_BERNSTEIN, _TO_BERNSTEIN)[:, 3 * _I + _J][3 * _I + _J, :]

NEWTON_ITERATIONS = 20


def quad9_cells(cells_file) -> np.ndarray:
    """The connectivity (n_cells, 9) from a snapshot cells file (VTK layout: count, then nodes).

    ``cells_file``: its path, or its loaded arrays (anything with ``cells`` and ``types``).
    """
    data = np.load(cells_file) if isinstance(cells_file, (str, Path)) else cells_file
    flat, types = np.asarray(data["cells"]), np.asarray(data["types"])
    if not np.all(np.isin(types, _QUAD9_TYPES)) or flat.size != 10 * types.size:
        raise ValueError("the snapshot cells are not all 9-node quadrilaterals (VTK type 28 or 70)")
    cells = flat.reshape(-1, 10)
    if not np.all(cells[:, 0] == 9):
        raise ValueError("the snapshot cells are not all 9-node quadrilaterals")
    return cells[:, 1:].astype(np.int64)


def _shape(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """1D quadratic Lagrange functions on the nodes 0, 1/2, 1 and their derivatives, (3, ...)."""
    return (
        np.stack([(2 * t - 1) * (t - 1), 4 * t * (1 - t), t * (2 * t - 1)]),
        np.stack([4 * t - 3, 4 - 8 * t, 4 * t - 1]),
    )


def shape9(r: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 9 cell functions in the cells' node order and their r and s derivatives, (k, 9) each."""
    Lr, dLr = _shape(r)
    Ls, dLs = _shape(s)
    return (Lr[_I] * Ls[_J]).T, (dLr[_I] * Ls[_J]).T, (Lr[_I] * dLs[_J]).T


def crossing(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local coordinates (r, s) where two fields on cells (node values (k, 9)) both vanish.

    Newton's method from the cells' centres, the iterates kept within half a cell of it; a pair
    leaves the iteration once its step is below 1e-12, so later iterations cost only the pairs
    still moving (those without a root in the cell, mostly). Whether the result is a root inside
    the cell is for the caller to check.
    """
    k = len(a)
    fields = np.zeros((2, k, 3, 3))
    fields[0][:, _I, _J], fields[1][:, _I, _J] = a, b
    r, s = np.full(k, 0.5), np.full(k, 0.5)
    active = np.arange(k)
    for _ in range(NEWTON_ITERATIONS):
        if not len(active):
            break
        Lr, dLr = _shape(r[active])
        Ls, dLs = _shape(s[active])
        f = fields[:, active]
        along_s, across_s = np.einsum("fkij,jk->fki", f, Ls), np.einsum("fkij,jk->fki", f, dLs)
        value = np.einsum("ik,fki->fk", Lr, along_s)
        d_r = np.einsum("ik,fki->fk", dLr, along_s)
        d_s = np.einsum("ik,fki->fk", Lr, across_s)
        det = d_r[0] * d_s[1] - d_s[0] * d_r[1]
        ok = np.abs(det) > 0
        det = np.where(ok, det, 1.0)
        step_r = np.where(ok, (d_s[1] * value[0] - d_s[0] * value[1]) / det, 0.0)
        step_s = np.where(ok, (d_r[0] * value[1] - d_r[1] * value[0]) / det, 0.0)
        r[active] = np.clip(r[active] - step_r, -0.5, 1.5)
        s[active] = np.clip(s[active] - step_s, -0.5, 1.5)
        active = active[ok & (np.abs(step_r) + np.abs(step_s) > 1e-12)]
    return r, s


def _merged_nodes(points: np.ndarray, tolerance: float, also: np.ndarray | None) -> np.ndarray:
    """A label per node, shared by nodes at one place: the copies a gather from several ranks makes.

    With ``also`` (the same nodes in another state) nodes are merged only if they coincide in both,
    so that distinct nodes that happen to touch in one state are kept apart.
    """
    n = len(points)
    pairs = cKDTree(points).query_pairs(tolerance, output_type="ndarray")
    if also is not None and len(pairs):
        pairs = pairs[np.linalg.norm(also[pairs[:, 0]] - also[pairs[:, 1]], axis=1) <= tolerance]
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def material_coordinate(
    points: np.ndarray,
    cells: np.ndarray,
    axis_point: np.ndarray,
    also: np.ndarray | None = None,
) -> np.ndarray:
    """The material coordinate xi1 [m] of every node, recovered from the geometry of a strip.

    ``points`` (n, 3) is a state of the tape's mid-surface [m], ``cells`` (n_cells, 9) its Q2
    connectivity on the structured strip mesh. xi1 is the shortest path length along the cells'
    lattice lines from the end of the strip nearer the hub axis (the root), which on a structured
    mesh is the arc length along the line xi2 = const through the node. Nodes gathered twice
    (once per rank holding them) are merged first; ``also`` is the same nodes in another state,
    in which copies must coincide too. Nodes in no cell get NaN.
    """
    x = np.asarray(points, dtype=float)
    n = len(x)
    used = np.unique(cells)
    size = float(np.ptp(x[used], axis=0).max())
    label = _merged_nodes(x, 1e-6 * size, None if also is None else np.asarray(also, dtype=float))
    c = label[cells]
    a, b = c[:, _LATTICE_EDGES[:, 0]].ravel(), c[:, _LATTICE_EDGES[:, 1]].ravel()
    # an edge two cells share once: a sparse matrix adds up repeated entries
    a, b = np.unique(np.stack([np.minimum(a, b), np.maximum(a, b)]), axis=1)
    rep = np.zeros(label.max() + 1, dtype=np.int64)
    rep[label] = np.arange(n)  # one original node per merged node, for its position
    weight = np.linalg.norm(x[rep[a]] - x[rep[b]], axis=1)
    m = label.max() + 1
    graph = coo_matrix((weight, (a, b)), shape=(m, m)).tocsr()
    # the strip's corners are the only cell corners that belong to a single cell
    corner_nodes, counts = np.unique(c[:, _CORNERS], return_counts=True)
    corners = corner_nodes[counts == 1]
    if len(corners) != 4:
        raise ValueError(f"not a strip of quadrilaterals: {len(corners)} corners instead of 4")
    d = dijkstra(graph, directed=False, indices=corners)
    # the corners of one end are a width apart, those of different ends at least a length
    partner = int(np.argmin(np.where(np.arange(4) == 0, np.inf, d[0, corners])))
    ends = [[0, partner], [k for k in range(4) if k not in (0, partner)]]
    spacing = float(weight[weight > 0].min())
    rel = x[rep[corners]] - np.asarray(axis_point, dtype=float)
    to_axis = np.hypot(rel[:, 0], rel[:, 2])
    root = min(ends, key=lambda e: to_axis[e].mean())
    # the end line: the nodes on the shortest path between the end's two corners
    i, j = root
    on_end = np.nonzero(d[i] + d[j] <= d[i, corners[j]] + 0.5 * spacing)[0]
    xi1 = dijkstra(graph, directed=False, indices=on_end, min_only=True)[label]
    xi1[~np.isfinite(xi1)] = np.nan  # nodes of no cell, nor copies of one
    return xi1
