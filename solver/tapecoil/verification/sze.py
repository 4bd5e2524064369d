"""Sze, Liu and Lo (2004)'s benchmarks of geometrically nonlinear shells: the roll-up cantilever,
the pinched semicylinder and the slit annular plate (physics brief Sec. 9)."""

from __future__ import annotations

import math
import time

import dolfinx
import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI

from tapecoil.config import SolverConfig
from tapecoil.core.dofs import global_size
from tapecoil.core.newton import SNESSolver
from tapecoil.geometry.meshes import FREE_END, ROOT, MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.edges import clamp, facet_condition
from tapecoil.models.shell import NaghdiShell, ShellMaterial
from tapecoil.verification.checks import CaseResult, Check, edge_average, solve_to_full_load, solver_prefix

ROLLUP_MESHES = {
    "coarse": MeshResolution(1, 24),
    "default": MeshResolution(2, 32),
    "fine": MeshResolution(4, 64),
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
    the root. Also checked: the tip on the exact circle at half turns. ``solver_config``:
    Newton and cut-back settings (``[solver]``; the defaults when None); the moment is stepped
    from 5 % to at most 10 % of its final value.
    """
    from tapecoil.core.stepping import Continuation

    L, b, h, E = 12.0, 1.0, 0.1, 1.2e6
    res = resolution or ROLLUP_MESHES["default"]
    strip = create_strip_mesh(comm, StripGeometry(math.inf, b, L), res)
    model = NaghdiShell(strip, ShellMaterial(E, 0.0, h), technology)
    M_max = 2 * math.pi * E * (b * h**3 / 12) / L
    moment = dolfinx.fem.Constant(strip.mesh, 0.0)
    work = moment / b * model.theta[1] * model.ds(FREE_END)
    root = clamp(model, ROOT)
    F = model.residual(work)
    settings = solver_config or SolverConfig()
    solver = SNESSolver.from_config(
        F, model.jacobian_form(F), model.q, root.bcs, settings, prefix=solver_prefix("rollup")
    )
    control = settings.control(initial_step=0.05, max_step=0.1, min_step=1e-6)
    checks, tips = [], []

    def set_load(t):
        moment.value = t * turns * M_max

    def record(step):
        theta = 2 * math.pi * turns * step.load
        tip = edge_average(model, model.u, FREE_END, b)
        exact = np.array([L * (math.sin(theta) / theta - 1), 0.0, -L * (1 - math.cos(theta)) / theta])
        tips.append((theta, tip, exact))

    stops = tuple(k / (2 * turns) for k in range(1, 2 * turns))
    t0 = time.perf_counter()
    run = Continuation(solver.solve, set_load, model.q, control, on_step=record).run(0.0, 1.0, stops)
    wall = time.perf_counter() - t0
    for theta, tip, exact in tips:
        k = theta / math.pi
        if abs(k - round(k)) < 1e-9:
            label = f"{k / 2:g} turn" + ("s" if k != 2 else "")
            checks.append(
                Check(f"tip error / L at {label}", float(np.linalg.norm(tip - exact) / L), 0.0, 0.01, True)
            )
    solver.destroy()
    return CaseResult(
        "rollup",
        checks,
        {
            "mesh": f"{res.along} x {res.across}",
            "dofs": global_size(model.W),
            "steps": len(run),
            "newton_iterations": [s.iterations for s in run],
            "tip": [[theta, *tip.tolist()] for theta, tip, _ in tips],
            "wall_time": wall,
        },
    )


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


def semicylinder(
    resolution: MeshResolution | None = None, comm=MPI.COMM_WORLD, solver_config: SolverConfig | None = None
) -> CaseResult:
    """Pinched semi-cylinder (Sze, Liu and Lo 2004): deflection under the load, 1.715 at P = 2000.

    R = 1.016, L = 3.048, h = 0.03, E = 2.0685e7, nu = 0.3. The whole semi-cylinder: one curved
    end clamped; on the straight edges (in the plane through the axis) the displacement normal to
    that plane and the rotation about the axis are zero; the point force P at the crown of the
    free end pushes towards the axis. Reference: the deflection there, 1.71505 (Sze's S4R table).
    ``solver_config``: Newton and cut-back settings (``[solver]``; the defaults when None); the
    force is stepped from 10 % to at most 20 % of P.
    """
    from tapecoil.core.dofs import node_value, owned_node_dofs
    from tapecoil.core.newton import PointForce
    from tapecoil.geometry.meshes import SIDE_NEG, SIDE_POS

    R, L, h, E, nu, P = 1.016, 3.048, 0.03, 2.0685e7, 0.3, 2000.0
    res = resolution or SEMICYLINDER_MESHES["default"]
    strip = create_strip_mesh(comm, StripGeometry(R, math.pi * R, L), res)
    model = NaghdiShell(strip, ShellMaterial(E, nu, h))
    bcs = list(clamp(model, ROOT).bcs)
    sides = np.concatenate([strip.facet_tags.find(SIDE_NEG), strip.facet_tags.find(SIDE_POS)])
    # u_z (normal to the plane of the edges) and theta_0 (the rotation about the axis) vanish
    bcs += [facet_condition(model, sub, sides)[1] for sub in ((0, 2), (1, 0))]
    load = dolfinx.fem.Constant(strip.mesh, 0.0)
    crown = (L, 0.0)
    force = PointForce(owned_node_dofs(model.W, (0, 2), crown), load)
    t0 = time.perf_counter()
    history = solve_to_full_load(
        model,
        model.residual(),
        bcs,
        lambda t: setattr(load, "value", t * P),
        solver_config or SolverConfig(),
        solver_prefix("semicylinder"),
        (0.1, 0.2),
        [force],
    )
    wall = time.perf_counter() - t0
    W = node_value(model.q, (0, 2), crown)
    return CaseResult(
        "semicylinder",
        [Check("deflection under the load at P = 2000", W, 1.71505, 0.02)],
        {
            "mesh": f"{res.along} x {res.across}",
            "dofs": global_size(model.W),
            "steps": len(history),
            "newton_iterations": [s.iterations for s in history],
            "wall_time": wall,
        },
    )


def slit_plate(
    resolution: MeshResolution | None = None, comm=MPI.COMM_WORLD, solver_config: SolverConfig | None = None
) -> CaseResult:
    """Slit annular plate under a line force at the free slit edge (Sze, Liu and Lo 2004).

    R_i = 6, R_o = 10, h = 0.03, E = 21e6, nu = 0. One slit edge clamped, the other loaded by
    0.8 per unit length (3.2 in all) normal to the plate. References: the deflections of the
    loaded edge at the inner radius (A) 13.891 and at the outer radius (B) 17.528.
    ``solver_config``: Newton and cut-back settings (``[solver]``; the defaults when None); the
    line force is stepped from 5 % to at most 10 % of its final value.
    """
    from tapecoil.geometry.surfaces import AnnulusGeometry

    Ri, Ro, h, E, p_max = 6.0, 10.0, 0.03, 21e6, 0.8
    res = resolution or SLIT_PLATE_MESHES["default"]
    strip = create_strip_mesh(comm, AnnulusGeometry(Ri, Ro), res)
    model = NaghdiShell(strip, ShellMaterial(E, 0.0, h))
    line_force = dolfinx.fem.Constant(strip.mesh, 0.0)
    work = line_force * model.u[2] * model.ds(FREE_END)  # xi_2 = r: ds is the physical length
    t0 = time.perf_counter()
    history = solve_to_full_load(
        model,
        model.residual(work),
        clamp(model, ROOT).bcs,
        lambda t: setattr(line_force, "value", t * p_max),
        solver_config or SolverConfig(),
        solver_prefix("slit-plate"),
        (0.05, 0.1),
    )
    wall = time.perf_counter() - t0
    from tapecoil.core.dofs import node_value

    wA = node_value(model.q, (0, 2), (2 * math.pi, Ri))
    wB = node_value(model.q, (0, 2), (2 * math.pi, Ro))
    return CaseResult(
        "slit-plate",
        [Check("w_A (inner radius)", wA, 13.891, 0.02), Check("w_B (outer radius)", wB, 17.528, 0.02)],
        {
            "mesh": f"{res.along} x {res.across}",
            "dofs": global_size(model.W),
            "steps": len(history),
            "newton_iterations": [s.iterations for s in history],
            "wall_time": wall,
        },
    )
