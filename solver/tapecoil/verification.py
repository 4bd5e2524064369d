"""Verification cases of the shell core, each returning computed values against references.

The CLI (``tapecoil verify``) and the tests run the same functions.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from . import theory
from .boundary import clamp
from .config import Config
from .geometry import FREE_END, ROOT, MeshResolution, StripGeometry, create_strip_mesh
from .shell import NaghdiShell, ShellMaterial
from .solvers import SNESSolver


@dataclass
class Check:
    """One computed quantity against its reference, with the tolerance it must meet."""

    name: str
    computed: float
    reference: float
    tolerance: float  # relative, or absolute when ``absolute``
    absolute: bool = False

    @property
    def error(self) -> float:
        if self.absolute:
            return abs(self.computed - self.reference)
        return abs(self.computed - self.reference) / abs(self.reference)

    @property
    def passed(self) -> bool:
        return bool(np.isfinite(self.computed)) and self.error <= self.tolerance


@dataclass
class CaseResult:
    """A verification case: its checks and the numbers that describe the run."""

    case: str
    checks: list[Check]
    info: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)


def assemble(form) -> float:
    """Assemble a scalar form over all ranks (collective)."""
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form))
    comm = form.ufl_domain().ufl_cargo().comm if hasattr(form, "ufl_domain") else MPI.COMM_WORLD
    return comm.allreduce(local, op=MPI.SUM)


def _edge_integral(model: NaghdiShell, integrand, tag: int) -> float:
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand * model.ds(tag)))
    return model.mesh.comm.allreduce(local, op=MPI.SUM)


def energies(model: NaghdiShell) -> dict[str, float]:
    """Membrane, bending and shear energies [J] at the current state (the solve's quadrature)."""
    comm = model.mesh.comm
    out = {}
    for name in ("membrane", "bending", "shear"):
        local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(getattr(model, f"energy_{name}")))
        out[name] = comm.allreduce(local, op=MPI.SUM)
    out["total"] = out["membrane"] + out["bending"] + out["shear"]
    return out


def quadratic_energies(model: NaghdiShell) -> dict[str, float]:
    """Energies of the linearised shell at the current state q: E_i = d^2 E_i(0)[q, q] / 2.

    The second-order Taylor term of each energy form about the (stress-free) reference,
    assembled with the quadrature the solve uses. The state is restored afterwards.
    """
    direction = model.q.copy()
    model.q.x.array[:] = 0.0
    comm = model.mesh.comm
    out = {}
    try:
        for name in ("membrane", "bending", "shear"):
            form = getattr(model, f"energy_{name}")
            second = ufl.derivative(ufl.derivative(form, model.q, direction), model.q, direction)
            out[name] = 0.5 * comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(second)), op=MPI.SUM)
    finally:
        model.q.x.array[:] = direction.x.array
    out["total"] = out["membrane"] + out["bending"] + out["shear"]
    return out


def tape_linear(config: Config, resolution: MeshResolution, technology: str = "mixed", comm=MPI.COMM_WORLD,
                rotation: float = 1e-4) -> CaseResult:
    """The benchmark tape clamped at the root, a small end moment about the width axis.

    The moment is applied as the axial traction (M/I)(z - z_c) h on the free end, the
    Saint-Venant distribution of beam bending about the section's centroidal axis, sized for an
    end rotation of about ``rotation`` [rad] so that the response is linear. Checks: strain
    energy = half the external work (same quadrature as the solve) to 1e-6, and the
    work-conjugate end rotation W / M against the beam limit M L / (E I) within 3 %.
    """
    tp = config.tape
    geom = StripGeometry.from_config(config)
    strip = create_strip_mesh(comm, geom, resolution)
    model = NaghdiShell(strip, ShellMaterial(tp.E, tp.nu, tp.h), technology)
    I = theory.arc_second_moment(tp.R, tp.alpha, tp.h)
    M = rotation * tp.E * I / tp.L
    beta = tp.alpha / 2
    z_c = tp.R * (1 - math.sin(beta) / beta)  # centroid of the arc
    z = model.phi0[2]
    I_membrane = _edge_integral(model, tp.h * (z - z_c) ** 2, FREE_END)
    traction = ufl.as_vector([M / I_membrane * (z - z_c) * tp.h, 0.0, 0.0])
    work = ufl.dot(traction, model.u) * model.ds(FREE_END)

    root = clamp(model, ROOT)
    F = model.residual(work)
    # one exact linear solve about the reference state: q = -J(0)^-1 F(0)
    solver = SNESSolver(F, model.jacobian_form(F), model.q, root.bcs, options={"snes_type": "ksponly"})
    t0 = time.perf_counter()
    result = solver.solve()
    wall = time.perf_counter() - t0
    W = _edge_integral(model, ufl.dot(traction, model.u), FREE_END)
    E = quadratic_energies(model)
    phi = W / M
    phi_beam = M * tp.L / (tp.E * I)
    solver.destroy()
    return CaseResult(
        "tape-linear",
        [
            Check("strain energy / (W/2)", E["total"] / (0.5 * W), 1.0, 1e-6),
            Check("end rotation / (M L / E I)", phi / phi_beam, 1.0, 0.03),
        ],
        {
            "technology": technology,
            "mesh": f"{resolution.along} x {resolution.across}",
            "dofs": model.W.dofmap.index_map.size_global * model.W.dofmap.index_map_bs,
            "linear_solve": result.reason_name,
            "converged": result.converged,
            "end_rotation": phi,
            "beam_rotation": phi_beam,
            "energy_split": {k: E[k] / E["total"] for k in ("membrane", "bending", "shear")},
            "wall_time": wall,
        },
    )


def _edge_average(model: NaghdiShell, expr, tag: int, length: float) -> np.ndarray:
    """Average of a vector expression over an edge of parameter length ``length`` (collective)."""
    return np.array([_edge_integral(model, expr[i], tag) / length for i in range(len(expr))])


def rollup(resolution: MeshResolution | None = None, turns: int = 2, comm=MPI.COMM_WORLD,
           control=None, technology: str = "psri") -> CaseResult:
    """Roll-up of a cantilever strip by an end moment (Sze, Liu and Lo 2004).

    L = 12, width 1, h = 0.1, E = 1.2e6, nu = 0; M_max = 2 pi E I / L rolls it into a full
    circle. The moment is conservative, work-conjugate to the end rotation theta_1 (the
    unbounded angle about the width axis), and grows to ``turns`` M_max. Check at every full
    turn: the tip (centre of the free end) within 1 % of L of the exact circle, i.e. back at
    the root. Also checked: the tip on the exact circle at half turns.
    """
    from .config import SolverConfig
    from .continuation import Continuation

    L, b, h, E = 12.0, 1.0, 0.1, 1.2e6
    res = resolution or MeshResolution(across=2, along=32)
    strip = create_strip_mesh(comm, StripGeometry(math.inf, b, L), res)
    model = NaghdiShell(strip, ShellMaterial(E, 0.0, h), technology)
    M_max = 2 * math.pi * E * (b * h**3 / 12) / L
    moment = dolfinx.fem.Constant(strip.mesh, 0.0)
    work = moment / b * model.theta[1] * model.ds(FREE_END)
    root = clamp(model, ROOT)
    F = model.residual(work)
    solver = SNESSolver(F, model.jacobian_form(F), model.q, root.bcs)
    control = control or SolverConfig(initial_step=0.05, max_step=0.1)
    checks, tips = [], []

    def set_load(t):
        moment.value = t * turns * M_max

    def record(step):
        theta = 2 * math.pi * turns * step.load
        tip = _edge_average(model, model.u, FREE_END, b)
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
            checks.append(Check(f"tip error / L at {label}", float(np.linalg.norm(tip - exact) / L), 0.0, 0.01, True))
    solver.destroy()
    return CaseResult(
        "rollup",
        checks,
        {
            "mesh": f"{res.along} x {res.across}",
            "dofs": model.W.dofmap.index_map.size_global * model.W.dofmap.index_map_bs,
            "steps": len(run),
            "newton_iterations": [s.iterations for s in run],
            "wall_time": wall,
        },
    )
