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
from the geometry by :func:`~tapecoil.measures.quad9.material_coordinate`: the arc length
along the mesh lines from the root end of the strip. Membrane strains along the tape are of
order 1e-3, so this differs from the reference xi1 by far less than any sensible exclusion
length (a fraction of a turn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from tapecoil.core.collective import raise_everywhere
from tapecoil.measures.quad9 import (
    BERNSTEIN_9,
    NEWTON_ITERATIONS,
    crossing,
    material_coordinate,
    quad9_cells,
    shape9,
)

__all__ = [
    "DEFAULT_PERCENTILES",
    "DEFAULT_REACH",
    "INSIDE_TOLERANCE",
    "NEWTON_ITERATIONS",
    "SeparationHistory",
    "TurnSeparation",
    "material_coordinate",
    "quad9_cells",
    "separation_history",
    "separation_measure",
    "snapshot_files",
    "turn_separation",
]

# Crossings found this far outside the cell (in local coordinates) still count: a half-line through
# an edge shared by two cells must not slip between them by rounding.
INSIDE_TOLERANCE = 1e-6
DEFAULT_PERCENTILES = (1.0, 5.0, 50.0)
DEFAULT_REACH = 10.0  # [h]: separations beyond this are not looked for


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
    B = np.einsum("ab,cbd->cad", BERNSTEIN_9, x[cells])
    Bxi = xi1[cells] @ BERNSTEIN_9.T
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
    r, s = crossing(a, b)
    N, _, _ = shape9(r, s)
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
    the contact that keeps the turns apart, and held to a lower bound (:func:`separation_bound`)
    when the turns rest on each other's real surfaces; on the spiral obstacle
    (``contact.turns = "spiral"``), which does not keep the turns off each other, it is reported
    without one. Computed on rank 0, where the snapshots are; every rank gets it
    (collective when ``comm`` is given; an error there is raised on every rank). None when the
    phase wrote no snapshots.
    """
    entry, error = None, None
    if comm is None or comm.rank == 0:
        try:
            entry = _separation_entry(directory, phase)
        except Exception as err:  # raised on every rank: the others wait in the broadcast
            error = err
    raise_everywhere(comm, error)
    return entry if comm is None else comm.bcast(entry, root=0)


def _separation_entry(directory: str | Path, phase: str) -> dict | None:
    """:func:`separation_measure`'s entry, on the rank that holds the snapshots."""
    from tapecoil.config import load_config
    from tapecoil.measures.measure import Measure

    files, _ = snapshot_files(directory, phase)
    if not files:
        return None
    history = separation_history(directory, phase)
    found = history.index is not None
    first = history.percentiles.get(1.0)
    config = load_config(Path(directory) / "config.toml")
    bound, sag = separation_bound(config)
    real = config.contact.turns != "spiral"
    return Measure(
        "smallest separation of distinct turns / h, from the snapshots [-]",
        history.global_minimum if found else None,
        bound,
        0.0 if real else None,
        "turns one thickness apart (physics brief Sec. 2): mid-surfaces h apart",
        (
            f"at least {bound:g} h: the turns one thickness apart, less the penalty's penetration "
            f"and the elements' quadratic interpolation of the coil, which lies up to "
            f"r_hub theta_e^4 / 512 = {sag:.2g} h inside the circle through the nodes (theta_e an "
            "element's angle on the hub), on either turn"
            if real
            else "a reading, without the bound: the spiral obstacle does not keep the turns off "
            f"each other (the turns' real contact, contact.turns = 'surface', keeps at least {bound:g} h)"
        ),
        bound="lower",
        extra={
            "at": history.t_min if found else None,
            "at_unit": "rad" if phase == "coiling" else "s",
            "snapshots": len(history.files),
            "lowest_1_percent": float(np.nanmin(first)) if found and first is not None else None,
            "quantity": "radial distance between the mid-surfaces of turns lying over each other"
            + ("" if found else " (no two turns lie over each other)"),
        },
    ).to_dict()


def separation_bound(config) -> tuple[float, float]:
    """The smallest separation of distinct turns / h a run of ``config`` must keep, and the
    interpolation's sag / h it allows for: 0.9 where the elements follow the coil to a
    hundredth of h (the sag of a quadratic element spanning theta_e of the hub, r_hub theta_e^4
    / 512, on either turn), 0.8 where they do not (a coarse mesh's elements span a radian of
    the coil: 0.2 h)."""
    from tapecoil.geometry.meshes import MeshResolution

    tp = config.tape
    element = tp.L / MeshResolution.from_config(config.mesh, tp.L).along
    theta = element / config.hub.radius
    sag = config.hub.radius * theta**4 / 512 / tp.h
    return (0.9 if 2 * sag <= 0.02 else 0.8), sag
