"""How close distinct turns of the coil come to each other, read from the surface geometry alone.

This is the independent check of the contact between turns: it uses nothing of the contact
formulation (no gap function, no penalty, no contact side), only the mid-surface points a run
gathered into ``snapshots/`` (:class:`tapecoil.core.output.ShellWriter`) and where the hub axis is
(:class:`tapecoil.hub.frame.HubFrame`). It measures as one would with a rule laid along a radius:

- for every node P, take the half-line from the hub axis through P, in the plane normal to the
  axis (the axis is along y): same polar angle, same axial coordinate y as P;
- find the cells of the tape that this half-line crosses, leaving out those parts whose material
  coordinate xi1 lies within ``exclusion_length`` of P's (P's own neighbourhood on its own turn);
- in each crossed cell solve for the local coordinates (r, s) of the crossing on the cell's
  biquadratic (Q2, 9-node) map by Newton's method, and read the distance from the axis there;
- the separation of P is the smallest |r_P - r_crossing| over the crossed cells: mid-surface to
  mid-surface, so h for two turns that touch, about 0 where two turns cross each other.

The smallest separation over the nodes (divided by h), where it is, and low percentiles of the
nodes' separations are the measure of a snapshot; :func:`separation_history` does this for every
snapshot of a phase in a results directory.

Units: lengths in metres (as written in the snapshots and the configuration); the separations
returned are divided by the thickness h.

The material coordinate. The snapshots hold the deformed surface, not the parameter coordinates
(xi1, xi2); unless the cells file carries them (an ``xi`` or ``xi1`` array), xi1 is recovered
from the geometry by :func:`material_coordinate`: the arc length along the mesh lines from the
root end of the strip. Membrane strains along the tape are of order 1e-3, so this differs from
the reference xi1 by far less than any sensible exclusion length (a fraction of a turn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
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
_BERNSTEIN_9 = np.kron(_TO_BERNSTEIN, _TO_BERNSTEIN)[:, 3 * _I + _J][3 * _I + _J, :]

NEWTON_ITERATIONS = 20
# Crossings found this far outside the cell (in local coordinates) still count: a half-line through
# an edge shared by two cells must not slip between them by rounding.
INSIDE_TOLERANCE = 1e-6
DEFAULT_PERCENTILES = (1.0, 5.0, 50.0)
DEFAULT_REACH = 10.0  # [h]: separations beyond this are not looked for


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


def _shape9(r: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 9 cell functions in the cells' node order and their r and s derivatives, (k, 9) each."""
    Lr, dLr = _shape(r)
    Ls, dLs = _shape(s)
    return (Lr[_I] * Ls[_J]).T, (dLr[_I] * Ls[_J]).T, (Lr[_I] * dLs[_J]).T


def _crossing(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


@dataclass
class TurnSeparation:
    """The separation between distinct turns in one state.

    Attributes:
        minimum: smallest separation over the nodes / h [-]; NaN when no node has another part
            of the tape within reach along its radius.
        node: index of the node where it occurs (-1 when none).
        xi1: material coordinate of that node [m].
        xi1_other: material coordinate of the other part of the tape at the crossing [m].
        position: the node's position [m].
        offset: (r_other - r_node) / h at the minimum [-]: > 0 when the nearer part lies outside.
        percentiles: percentile [%] -> that percentile of the nodes' separations / h.
        per_node: every node's separation / h (NaN where nothing is within reach).
        measured: number of nodes with a separation.
    """

    minimum: float
    node: int
    xi1: float
    xi1_other: float
    position: np.ndarray
    offset: float
    percentiles: dict[float, float]
    per_node: np.ndarray = field(repr=False)
    measured: int


def turn_separation(
    points: np.ndarray,
    cells: np.ndarray,
    xi1: np.ndarray,
    axis_point: np.ndarray,
    h: float,
    exclusion_length: float,
    reach: float | None = None,
    percentiles: tuple[float, ...] = DEFAULT_PERCENTILES,
) -> TurnSeparation:
    """The radial separation between distinct parts of the tape, over each node, / h.

    Args:
        points: (n, 3) mid-surface positions of the nodes [m].
        cells: (n_cells, 9) Q2 connectivity in VTK order (:func:`quad9_cells`).
        xi1: (n,) material coordinate along the tape of each node [m] (NaN: node not measured).
        axis_point: a point of the hub axis [m]; the axis is along y.
        h: tape thickness [m]; the separations are returned divided by it.
        exclusion_length: parts of the tape within this material distance of a node are its own
            neighbourhood and not measured against it [m]; less than the length of the innermost
            turn (2 pi r_hub), more than nothing (pi r_hub is a good choice).
        reach: separations up to this are looked for [m] (default 10 h); a node with nothing
            closer along its radius gets NaN.
        percentiles: which percentiles [%] of the nodes' separations to report.
    """
    x = np.asarray(points, dtype=float)
    cells = np.asarray(cells, dtype=np.int64)
    xi1 = np.asarray(xi1, dtype=float)
    A = np.asarray(axis_point, dtype=float)
    reach = DEFAULT_REACH * h if reach is None else float(reach)
    n = len(x)

    rel = x - A
    rho = np.hypot(rel[:, 0], rel[:, 2])
    valid = np.isfinite(xi1) & (rho > 0)
    ex = np.where(valid, rel[:, 0] / np.where(rho > 0, rho, 1.0), 0.0)  # radial unit vector (x, z)
    ez = np.where(valid, rel[:, 2] / np.where(rho > 0, rho, 1.0), 0.0)

    # control points of each cell's Bernstein form: the cell lies in their convex hull
    B = np.einsum("ab,cbd->cad", _BERNSTEIN_9, x[cells])
    Bxi = xi1[cells] @ _BERNSTEIN_9.T
    centre = B.mean(axis=1)
    radius = np.linalg.norm(B - centre[:, None, :], axis=2).max(axis=1)
    ylo, yhi = B[:, :, 1].min(axis=1), B[:, :, 1].max(axis=1)
    xlo, xhi = np.nanmin(Bxi, axis=1), np.nanmax(Bxi, axis=1)

    # a crossing within reach lies within reach of P and in the cell's hull: a ball test first
    tree_nodes = cKDTree(x[valid])
    tree_cells = cKDTree(centre)
    found = tree_nodes.sparse_distance_matrix(tree_cells, radius.max() + reach, output_type="ndarray")
    p = np.nonzero(valid)[0][found["i"]]
    c = found["j"].astype(np.int64)
    keep = (found["v"] <= radius[c] + reach) & (ylo[c] <= x[p, 1]) & (yhi[c] >= x[p, 1])
    # a cell wholly within the exclusion window is P's own neighbourhood
    keep &= ~((xlo[c] > xi1[p] - exclusion_length) & (xhi[c] < xi1[p] + exclusion_length))
    p, c = p[keep], c[keep]
    # the half-plane of P's polar angle must cut the hull, within reach of P's radius
    Bc = B[c] - A
    across = Bc[:, :, 0] * -ez[p, None] + Bc[:, :, 2] * ex[p, None]
    along = Bc[:, :, 0] * ex[p, None] + Bc[:, :, 2] * ez[p, None]
    keep = (across.min(axis=1) <= 0) & (across.max(axis=1) >= 0)
    keep &= (along.max(axis=1) >= rho[p] - reach) & (along.min(axis=1) <= rho[p] + reach)
    keep &= along.max(axis=1) > 0
    p, c = p[keep], c[keep]

    # Newton's method on the crossing: (X(r, s) - A) . n = 0 (the half-plane), X_y(r, s) = y_P
    Xc = x[cells[c]] - A
    a = Xc[:, :, 0] * -ez[p, None] + Xc[:, :, 2] * ex[p, None]
    b = Xc[:, :, 1] - (x[p, 1] - A[1])[:, None]
    r, s = _crossing(a, b)
    N, _, _ = _shape9(r, s)
    residual = np.hypot((N * a).sum(1), (N * b).sum(1))
    along = (N * (Xc[:, :, 0] * ex[p, None] + Xc[:, :, 2] * ez[p, None])).sum(1)
    xi_other = (N * xi1[cells[c]]).sum(1)
    inside = (np.minimum(r, s) >= -INSIDE_TOLERANCE) & (np.maximum(r, s) <= 1 + INSIDE_TOLERANCE)
    hit = inside & (residual <= 1e-9 * radius[c]) & (along > 0)
    hit &= np.abs(xi_other - xi1[p]) >= exclusion_length
    gap = np.where(hit, np.abs(along - rho[p]), np.inf)
    hit &= gap <= reach
    p, gap, along, xi_other = p[hit], gap[hit], along[hit], xi_other[hit]

    per_node = np.full(n, np.inf)
    np.minimum.at(per_node, p, gap)
    per_node = np.where(np.isfinite(per_node), per_node / h, np.nan)
    measured = int(np.isfinite(per_node).sum())
    if not len(gap):
        nan = math.nan
        return TurnSeparation(
            nan, -1, nan, nan, np.full(3, nan), nan, dict.fromkeys(percentiles, nan), per_node, 0
        )
    k = int(np.argmin(gap))
    node = int(p[k])
    values = per_node[np.isfinite(per_node)]
    return TurnSeparation(
        minimum=float(gap[k] / h),
        node=node,
        xi1=float(xi1[node]),
        xi1_other=float(xi_other[k]),
        position=x[node].copy(),
        offset=float((along[k] - rho[node]) / h),
        percentiles={
            q: float(v) for q, v in zip(percentiles, np.percentile(values, percentiles), strict=True)
        },
        per_node=per_node,
        measured=measured,
    )


@dataclass
class SeparationHistory:
    """The separation between turns in every snapshot of a phase.

    Attributes:
        phase: the phase the snapshots belong to ("coiling", "deployment").
        files: the snapshot files, in order.
        t: their times (hub angle [rad] in coiling, time [s] in deployment).
        minimum: smallest separation / h per snapshot (NaN: no two turns over each other).
        xi1: material coordinate [m] of the node where it occurs.
        percentiles: percentile [%] -> its value / h per snapshot.
        measured: nodes with a separation, per snapshot.
        h, exclusion_length, reach: what was measured with [m].
    """

    phase: str
    files: list[Path]
    t: np.ndarray
    minimum: np.ndarray
    xi1: np.ndarray
    percentiles: dict[float, np.ndarray]
    measured: np.ndarray
    h: float
    exclusion_length: float
    reach: float

    @property
    def index(self) -> int | None:
        """Position of the snapshot with the smallest separation (None when none has one)."""
        if not np.isfinite(self.minimum).any():
            return None
        return int(np.nanargmin(self.minimum))

    @property
    def global_minimum(self) -> float:
        """The smallest separation / h over the snapshots (NaN when none has one)."""
        return math.nan if self.index is None else float(self.minimum[self.index])

    @property
    def t_min(self) -> float:
        """The time of the snapshot with the smallest separation."""
        return math.nan if self.index is None else float(self.t[self.index])

    @property
    def file_min(self) -> Path | None:
        """The snapshot with the smallest separation."""
        return None if self.index is None else self.files[self.index]


def snapshot_files(directory: str | Path, phase: str) -> tuple[list[Path], Path]:
    """A phase's snapshot files in order and its cells file, in ``directory/snapshots``."""
    folder = Path(directory) / "snapshots"
    cells = folder / f"{phase}_cells.npz"
    files = sorted(folder.glob(f"{phase}_[0-9]*.npz"))
    if not cells.is_file() or not files:
        raise FileNotFoundError(f"no {phase} snapshots in {folder}")
    return files, cells


def separation_history(
    directory: str | Path,
    phase: str = "coiling",
    r_hub: float | None = None,
    h: float | None = None,
    sense: str | None = None,
    exclusion_length: float | None = None,
    reach: float | None = None,
    percentiles: tuple[float, ...] = DEFAULT_PERCENTILES,
    every: int = 1,
) -> SeparationHistory:
    """:func:`turn_separation` for the snapshots of ``phase`` in a results directory.

    ``r_hub`` [m], ``h`` [m] and ``sense`` place the hub axis (HubFrame); those not given are read
    from the run's config.toml. ``exclusion_length`` defaults to pi r_hub, half the innermost
    turn; ``reach`` to 10 h. ``every``: measure every this many snapshots (the last one always).
    xi1 comes from the cells file when it has it, else from the phase's first snapshot.
    """
    from tapecoil.hub.frame import HubFrame

    if r_hub is None or h is None or sense is None:
        from tapecoil.config import load_config

        config = load_config(Path(directory) / "config.toml")
        r_hub = config.hub.radius if r_hub is None else r_hub
        h = config.tape.h if h is None else h
        sense = config.coiling.sense if sense is None else sense
    axis_point = HubFrame(r_hub, h, sense).axis_point
    exclusion_length = math.pi * r_hub if exclusion_length is None else exclusion_length
    reach = DEFAULT_REACH * h if reach is None else reach

    files, cells_file = snapshot_files(directory, phase)
    chosen = sorted(set(range(0, len(files), max(1, every))) | {len(files) - 1})
    files = [files[i] for i in chosen]
    with np.load(cells_file) as data:
        cells = quad9_cells(data)
        xi = next((np.asarray(data[k]) for k in ("xi1", "xi") if k in data.files), None)
    if xi is not None:
        xi1 = xi if xi.ndim == 1 else xi[:, 0]
    else:
        with np.load(files[0]) as first, np.load(files[-1]) as last:
            xi1 = material_coordinate(first["points"], cells, axis_point, also=last["points"])

    t, minimum, where, measured = [], [], [], []
    values = {q: [] for q in percentiles}
    for f in files:
        with np.load(f) as snap:
            t.append(float(snap["t"]))
            m = turn_separation(
                snap["points"], cells, xi1, axis_point, h, exclusion_length, reach, percentiles
            )
        minimum.append(m.minimum)
        where.append(m.xi1)
        measured.append(m.measured)
        for q in percentiles:
            values[q].append(m.percentiles[q])
    return SeparationHistory(
        phase=phase,
        files=files,
        t=np.array(t),
        minimum=np.array(minimum),
        xi1=np.array(where),
        percentiles={q: np.array(v) for q, v in values.items()},
        measured=np.array(measured),
        h=h,
        exclusion_length=exclusion_length,
        reach=reach,
    )


def separation_measure(directory: str | Path, phase: str, comm=None) -> dict | None:
    """The smallest separation of distinct turns over a phase's snapshots, as a measure entry.

    Read from the geometry of the snapshots alone (:func:`separation_history`), independently of
    the contact that keeps the turns apart. Reported without a tolerance: with the default
    ``contact.turns = "spiral"`` the turns rest on a prescribed obstacle and this is what that
    obstacle lets them do. Computed on rank 0, where the snapshots are; every rank gets it
    (collective when ``comm`` is given). None when the phase wrote no snapshots.
    """
    from tapecoil.measures.measure import Measure

    entry = None
    if comm is None or comm.rank == 0:
        files, _ = snapshot_files(directory, phase)
        if files:
            history = separation_history(directory, phase)
            found = history.index is not None
            first = history.percentiles.get(1.0)
            entry = Measure(
                "smallest separation of distinct turns / h, from the snapshots [-]",
                history.global_minimum if found else None,
                1.0,
                None,
                "turns one thickness apart (physics brief Sec. 2): mid-surfaces h apart",
                extra={
                    "at": history.t_min if found else None,
                    "at_unit": "rad" if phase == "coiling" else "s",
                    "snapshots": len(history.files),
                    "lowest_1_percent": float(np.nanmin(first)) if found and first is not None else None,
                    "quantity": "radial distance between the mid-surfaces of turns lying over each other"
                    + ("" if found else " (no two turns lie over each other)"),
                },
            ).to_dict()
    return entry if comm is None else comm.bcast(entry, root=0)
