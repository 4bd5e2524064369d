"""Sze, Liu and Lo (2004)'s hinged cylindrical roof under a central point load, followed by
arc-length continuation through its snaps (:mod:`tapecoil.models.paths`).

R = 2540, length 508, 0.1 rad each side of the crown, E = 3102.75, nu = 0.3; the straight
edges hinged (held in place, free to turn), the curved edges free, the point force P at the
crown's centre towards the axis. h = 12.7 snaps through (the load passes a maximum and falls);
h = 6.35 also snaps back (the deflection under the load turns back). One quarter is solved, on
the planes of symmetry through the centre, with a quarter of P.

References: the first maximum of the load along the path and the deflection there, from Sze,
Liu and Lo, Finite Elem. Anal. Des. 40 (2004) 1551-1569, Tables 9a and 9d (their P/Pmax with
Pmax = 3000), as transcribed with the source named in the public validation notebooks of the
``panels`` project: 0.7421 Pmax at w = 11.293 (h = 12.7), 0.1953 Pmax at w = 12.892 (h =
6.35). The limit load is checked within 1 %. Their deflection is that of the table's point
of largest load, not of the maximum itself, where the path is flat: it is reported, not checked.
"""

from __future__ import annotations

import math

import numpy as np
from mpi4py import MPI

from tapecoil.config import SolverConfig
from tapecoil.core.arclength import ArcLengthSettings
from tapecoil.core.dofs import global_size
from tapecoil.core.stability import StabilityAnalysis
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.geometry.surfaces import MappedSurface
from tapecoil.models.paths import shell_path
from tapecoil.models.problem import ShellProblem
from tapecoil.models.shell import ShellMaterial
from tapecoil.verification.checks import CaseResult, Check, solver_prefix

RADIUS, LENGTH, HALF_ANGLE, YOUNG, POISSON = 2540.0, 508.0, 0.1, 3102.75, 0.3
SZE_PMAX = 3000.0
# (P/Pmax, w) at the first load maximum, Sze et al. (2004) Tables 9a and 9d
SZE_ROOF_LIMIT = {12.7: (0.7421, 11.293), 6.35: (0.1953, 12.892)}
LIMIT_TOLERANCE = 0.01
# the deflection under the load at which the path ends: past both snaps, as far as Sze's curves
END_DEFLECTION = 30.0

# elements of the quarter (across the arc, along the length)
ROOF_MESHES = {
    "coarse": MeshResolution(6, 6),
    "default": MeshResolution(8, 8),
    "fine": MeshResolution(12, 12),
}


def roof_problem(
    h: float, resolution: MeshResolution, comm=MPI.COMM_WORLD, name: str = "roof"
) -> ShellProblem:
    """The quarter roof of thickness ``h``: x from the free curved edge (0) to the centre
    (LENGTH / 2), the arc length s from the crown (0) to the hinged edge; lambda = P, the whole
    roof's load (a quarter of it on the quarter), towards the axis (+z)."""
    surface = MappedSurface(
        lambda xi, ops: (xi[0], RADIUS * ops.sin(xi[1] / RADIUS), RADIUS * (1 - ops.cos(xi[1] / RADIUS))),
        ((0.0, LENGTH / 2), (0.0, HALF_ANGLE * RADIUS)),
    )
    problem = ShellProblem(surface, resolution, ShellMaterial(YOUNG, POISSON, h), comm=comm, name=name)
    problem.hinge("xi2_max")
    problem.symmetry_plane("xi1_max", normal=(1.0, 0.0, 0.0))
    problem.symmetry_plane("xi2_min", normal=(0.0, 1.0, 0.0))
    problem.point_force((LENGTH / 2, 0.0), force=(0.0, 0.0, 0.25))
    return problem


def roof_curve(
    h: float,
    resolution: MeshResolution,
    comm=MPI.COMM_WORLD,
    *,
    end_deflection: float = END_DEFLECTION,
    stability: bool = True,
    solver_config: SolverConfig | None = None,
    name: str = "roof",
) -> dict:
    """The load-deflection path of the roof of thickness ``h`` up to ``end_deflection`` under
    the load: points (P, w, stable), the located critical points, steps, Newton iterations,
    dofs and wall times (collective)."""
    problem = roof_problem(h, resolution, comm, name)
    centre = (LENGTH / 2, 0.0)
    P_guess = SZE_ROOF_LIMIT[h][0] * SZE_PMAX
    settings = ArcLengthSettings(first_step=0.1 * P_guess, max_step=4.0, min_step=1e-3, rtol=1e-8, atol=1e-10)
    path = shell_path(
        problem,
        settings,
        stability=StabilityAnalysis(3, prefix=f"{name}_stability_") if stability else None,
        solver_config=solver_config,
        prefix=solver_prefix(name),
    )
    curve = []

    def record(point):
        w = float(problem.displacement_at(centre)[2])
        curve.append((point.load, w, point.stable, point.eigenvalues[0] if point.eigenvalues else math.nan))

    critical = []
    try:
        path.run(
            0.0,
            20 * P_guess,
            load_min=-20 * P_guess,
            stop=lambda _p: curve[-1][1] >= end_deflection,
            on_point=record,
        )
        for c in path.critical:  # the deflection of each located critical state
            path.system.set_state(c.state, c.load)
            w = float(problem.displacement_at(centre)[2])
            critical.append((c.kind, c.load, w, c.eigenvalue, c.initial_eigenvalue, c.located_in))
    finally:
        path.destroy()
    return {
        "thickness": h,
        "curve": curve,
        "critical": critical,
        "steps": len(path.points) - 1,
        "newton_iterations": [p.iterations for p in path.points[1:]],
        "halvings": sum(p.halvings for p in path.points),
        "dofs": global_size(problem.model.W),
        "mesh": f"{resolution.across} x {resolution.along} (quarter)",
        "wall_time": path.timings["steps"],
        "stability_time": path.timings["stability"],
        "locate_time": path.timings["locate"],
    }


def turning_points(values) -> int:
    """How many times a sequence turns back (its differences change sign)."""
    d = np.diff(np.asarray(values, dtype=float))
    d = d[d != 0]
    return int(np.count_nonzero(np.diff(np.sign(d))))


def roof(
    h: float, resolution: MeshResolution | None = None, comm=MPI.COMM_WORLD, solver_config=None
) -> CaseResult:
    """The roof's case (collective): the load-deflection curve through its snaps, the first
    limit load and the deflection there against Sze's, the eigenvalue through zero there, and
    the snap-back of the thin roof (the deflection turns back, then forward again)."""
    label = {12.7: "roof-snap-through", 6.35: "roof-snap-back"}[h]
    result = roof_curve(
        h,
        resolution or ROOF_MESHES["default"],
        comm,
        solver_config=solver_config,
        name=label.replace("-", "_"),
    )
    ratio, w_ref = SZE_ROOF_LIMIT[h]
    limits = [c for c in result["critical"] if c[0] == "limit"]
    curve = result["curve"]
    checks = []
    if limits:
        _, P_lim, w_lim, eigenvalue, initial, _ = limits[0]
        checks.append(Check("first limit load P", P_lim, ratio * SZE_PMAX, LIMIT_TOLERANCE))
        checks.append(Check("eigenvalue at the limit point / at rest", eigenvalue / initial, 0.0, 1e-4, True))
        result["limit_deflection"] = w_lim
        result["sze_deflection_at_largest_load"] = w_ref
    else:
        checks.append(Check("first limit load P (none located)", math.nan, ratio * SZE_PMAX, LIMIT_TOLERANCE))
    # through both snaps: the load's maximum and then its minimum, each an eigenvalue through zero
    checks.append(Check("limit points located (load max, min)", len(limits), 2, 0.0, True))
    w_turns = turning_points([p[1] for p in curve])
    checks.append(Check("turns of the deflection (snap-back: 2)", w_turns, 2 if h == 6.35 else 0, 0.0, True))
    return CaseResult(label, checks, result)
