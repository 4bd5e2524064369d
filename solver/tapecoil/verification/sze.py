"""Sze, Liu and Lo (2004)'s benchmarks of geometrically nonlinear shells: the roll-up cantilever,
the cantilever under end shear, the pinched semicylinder and the slit annular plate (physics
brief Sec. 9), each stated as a :class:`~tapecoil.models.problem.ShellProblem`: surface,
material, supports, loads in their own units, and the load steps."""

from __future__ import annotations

import math

import numpy as np
from mpi4py import MPI

from tapecoil.config import SolverConfig
from tapecoil.core.dofs import global_size
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.geometry.surfaces import AnnulusGeometry, StripGeometry
from tapecoil.models.problem import ShellProblem
from tapecoil.models.shell import ShellMaterial
from tapecoil.verification.checks import CaseResult, Check, solver_prefix

ROLLUP_MESHES = {
    "coarse": MeshResolution(1, 24),
    "default": MeshResolution(2, 32),
    "fine": MeshResolution(4, 64),
}


SEMICYLINDER_MESHES = {
    "coarse": MeshResolution(12, 12),
    "default": MeshResolution(20, 20),
    "fine": MeshResolution(32, 32),
}


SLIT_PLATE_MESHES = {
    "coarse": MeshResolution(4, 32),
    "default": MeshResolution(6, 48),
    "fine": MeshResolution(10, 80),
}


def _info(problem: ShellProblem, history, **extra) -> dict:
    res = problem.strip.resolution
    return {
        "mesh": f"{res.along} x {res.across}",
        "dofs": global_size(problem.model.W),
        "steps": len(history),
        "newton_iterations": [s.iterations for s in history],
        # every attempt's, the ones cut back included
        "newton_iterations_total": problem.newton_iterations,
        "wall_time": problem.wall_time,
        **extra,
    }


def rollup(
    resolution: MeshResolution | None = None,
    turns: int = 2,
    comm=MPI.COMM_WORLD,
    solver_config: SolverConfig | None = None,
    technology: str = "psri",
) -> CaseResult:
    """Roll-up of a cantilever strip by an end moment (Sze, Liu and Lo 2004).

    L = 12, width 1, h = 0.1, E = 1.2e6, nu = 0; M_max = 2 pi E I / L rolls it into a full
    circle. The moment is conservative, work-conjugate to the end rotation theta_1 (the
    unbounded angle about the width axis), and grows to ``turns`` M_max. Check at every full
    turn: the tip (centre of the free end) within 1 % of L of the exact circle, i.e. back at
    the root. Also checked: the tip on the exact circle at half turns. ``solver_config``: Newton and cut-back
    settings (``[solver]``; the defaults when None); the moment is stepped from 5 % to at most
    10 % of its final value.
    """
    L, b, h, E = 12.0, 1.0, 0.1, 1.2e6
    problem = ShellProblem(
        StripGeometry(math.inf, b, L),
        resolution or ROLLUP_MESHES["default"],
        ShellMaterial(E, 0.0, h),
        comm=comm,
        technology=technology,
    )
    problem.clamp("xi1_min")
    problem.edge_moment("xi1_max", moment=1 / b)  # lambda = the end moment [N m]
    M_max = 2 * math.pi * E * (b * h**3 / 12) / L
    tips = []

    def record(step):
        theta = 2 * math.pi * step.load / M_max
        tip = problem.edge_average("xi1_max", problem.model.u)
        exact = np.array([L * (math.sin(theta) / theta - 1), 0.0, -L * (1 - math.cos(theta)) / theta])
        tips.append((theta, tip, exact))

    M = turns * M_max
    history = problem.solve(
        M,
        first_step=0.05 * M,
        max_step=0.1 * M,
        stops=tuple(k * M_max / 2 for k in range(1, 2 * turns)),
        on_step=record,
        solver_config=solver_config,
        prefix=solver_prefix("rollup"),
    )
    checks = []
    for theta, tip, exact in tips:
        k = theta / math.pi
        if abs(k - round(k)) < 1e-9:
            label = f"{k / 2:g} turn" + ("s" if k != 2 else "")
            checks.append(
                Check(f"tip error / L at {label}", float(np.linalg.norm(tip - exact) / L), 0.0, 0.01, True)
            )
    tip_table = [[theta, *tip.tolist()] for theta, tip, _ in tips]
    return CaseResult("rollup", checks, _info(problem, history, tip=tip_table))


CANTILEVER_MESHES = {
    "coarse": MeshResolution(across=1, along=8),
    "default": MeshResolution(across=1, along=16),
    "fine": MeshResolution(across=2, along=32),
}


def cantilever_shear(
    resolution: MeshResolution | None = None, comm=MPI.COMM_WORLD, solver_config: SolverConfig | None = None
) -> CaseResult:
    """Cantilever strip under an end shear force (Sze, Liu and Lo 2004).

    L = 10, width 1, h = 0.1, E = 1.2e6, nu = 0; the free end carries P = 4 spread evenly over
    its width, fixed in direction (normal to the undeformed strip). References: the tip's
    displacements at P = 4, -u = 3.286 along the strip and w = 6.698 across it, within 2 %
    (Sze's converged values; the tip deflects by 0.67 L, a large rotation of the end).
    ``solver_config``: Newton and cut-back settings; the force is stepped from 5 % to at most
    10 % of P.
    """
    L, b, h, E, P = 10.0, 1.0, 0.1, 1.2e6, 4.0
    problem = ShellProblem(
        StripGeometry(math.inf, b, L),
        resolution or CANTILEVER_MESHES["default"],
        ShellMaterial(E, 0.0, h),
        comm=comm,
    )
    problem.clamp("xi1_min")
    problem.edge_force("xi1_max", force=(0.0, 0.0, 1 / b))  # lambda = the end force [N]
    history = problem.solve(
        P,
        first_step=0.05 * P,
        max_step=0.1 * P,
        solver_config=solver_config,
        prefix=solver_prefix("cantilever-shear"),
    )
    u, _, w = problem.displacement_at((L, 0.0))
    checks = [Check("tip -u at P = 4", -u, 3.286, 0.02), Check("tip w at P = 4", w, 6.698, 0.02)]
    return CaseResult("cantilever-shear", checks, _info(problem, history))


def semicylinder(
    resolution: MeshResolution | None = None, comm=MPI.COMM_WORLD, solver_config: SolverConfig | None = None
) -> CaseResult:
    """Pinched semi-cylinder (Sze, Liu and Lo 2004): deflection under the load, 1.715 at P = 2000.

    R = 1.016, L = 3.048, h = 0.03, E = 2.0685e7, nu = 0.3. The whole semi-cylinder: one curved
    end clamped; its straight edges lie on the plane through the axis, a plane of symmetry of
    the whole cylinder; the point force P at the crown of the free end pushes towards the axis.
    Reference: the deflection there, 1.71505 (Sze's S4R table). ``solver_config``: Newton and
    cut-back settings; the force is stepped from 10 % to at most 20 % of P.
    """
    R, L, h, E, nu, P = 1.016, 3.048, 0.03, 2.0685e7, 0.3, 2000.0
    problem = ShellProblem(
        StripGeometry(R, math.pi * R, L),
        resolution or SEMICYLINDER_MESHES["default"],
        ShellMaterial(E, nu, h),
        comm=comm,
    )
    problem.clamp("xi1_min")
    for side in ("xi2_min", "xi2_max"):
        problem.symmetry_plane(side, normal=(0.0, 0.0, 1.0))
    crown = (L, 0.0)
    problem.point_force(crown, force=(0.0, 0.0, 1.0))  # lambda = P [N], towards the axis (+z)
    history = problem.solve(
        P,
        first_step=0.1 * P,
        max_step=0.2 * P,
        solver_config=solver_config,
        prefix=solver_prefix("semicylinder"),
    )
    W = problem.displacement_at(crown)[2]
    checks = [Check("deflection under the load at P = 2000", W, 1.71505, 0.02)]
    return CaseResult("semicylinder", checks, _info(problem, history))


def slit_plate(
    resolution: MeshResolution | None = None, comm=MPI.COMM_WORLD, solver_config: SolverConfig | None = None
) -> CaseResult:
    """Slit annular plate under a line force at the free slit edge (Sze, Liu and Lo 2004).

    R_i = 6, R_o = 10, h = 0.03, E = 21e6, nu = 0. One slit edge clamped, the other loaded by
    0.8 per unit length (3.2 in all) normal to the plate. References: the deflections of the
    loaded edge at the inner radius (A) 13.891 and at the outer radius (B) 17.528.
    ``solver_config``: Newton and cut-back settings; the line force is stepped from 5 % to at
    most 10 % of its final value.
    """
    Ri, Ro, h, E, p_max = 6.0, 10.0, 0.03, 21e6, 0.8
    problem = ShellProblem(
        AnnulusGeometry(Ri, Ro),
        resolution or SLIT_PLATE_MESHES["default"],
        ShellMaterial(E, 0.0, h),
        comm=comm,
    )
    problem.clamp("xi1_min")
    problem.edge_force("xi1_max", force=(0.0, 0.0, 1.0))  # lambda = the line force [N/m]
    history = problem.solve(
        p_max,
        first_step=0.05 * p_max,
        max_step=0.1 * p_max,
        solver_config=solver_config,
        prefix=solver_prefix("slit-plate"),
        # full Newton steps from the flat plate raise the residual past PETSc's divergence test
        # (its default: 1e4 times the first residual) in their first iteration, then converge in
        # a few more: the test would cut every step back, for many times the load steps
        options={"snes_divergence_tolerance": 1e300},
    )
    wA = problem.displacement_at((2 * math.pi, Ri))[2]
    wB = problem.displacement_at((2 * math.pi, Ro))[2]
    checks = [Check("w_A (inner radius)", wA, 13.891, 0.02), Check("w_B (outer radius)", wB, 17.528, 0.02)]
    return CaseResult("slit-plate", checks, _info(problem, history))
