"""Verification cases of the shell core, each returning computed values against references.

The CLI (``tapecoil verify``) and the tests run the same functions.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil import theory
from tapecoil.config import Config, SolverConfig
from tapecoil.core.dofs import cell_midpoint_values, global_scalar, global_size
from tapecoil.core.newton import SNESSolver
from tapecoil.geometry.meshes import FREE_END, ROOT, MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.edges import EdgeMotion, clamp, facet_condition
from tapecoil.models.shell import NaghdiShell, ShellMaterial
from tapecoil.verification import CASES


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
        # a Python bool: numpy's bool would reach the JSON of ``tapecoil verify`` as 1.0
        return bool(np.isfinite(self.computed) and self.error <= self.tolerance)


@dataclass
class CaseResult:
    """A verification case: its checks and the numbers that describe the run."""

    case: str
    checks: list[Check]
    info: dict = field(default_factory=dict)
    model: object = field(default=None, repr=False)  # the solved NaghdiShell, for pictures

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)


def _edge_integral(model: NaghdiShell, integrand, tag: int) -> float:
    return global_scalar(integrand * model.ds(tag), model.mesh.comm)


def energies(model: NaghdiShell) -> dict[str, float]:
    """Membrane, bending and shear energies [J] at the current state (the solve's quadrature)."""
    names = ("membrane", "bending", "shear")
    out = {name: global_scalar(getattr(model, f"energy_{name}"), model.mesh.comm) for name in names}
    out["total"] = out["membrane"] + out["bending"] + out["shear"]
    return out


def quadratic_energies(model: NaghdiShell) -> dict[str, float]:
    """Energies of the linearised shell at the current state q: E_i = d^2 E_i(0)[q, q] / 2.

    The second-order Taylor term of each energy form about the (stress-free) reference,
    assembled with the quadrature the solve uses. The state is restored afterwards.
    """
    direction = model.q.copy()
    model.q.x.array[:] = 0.0
    out = {}
    try:
        for name in ("membrane", "bending", "shear"):
            form = getattr(model, f"energy_{name}")
            second = ufl.derivative(ufl.derivative(form, model.q, direction), model.q, direction)
            out[name] = 0.5 * global_scalar(second, model.mesh.comm)
    finally:
        model.q.x.array[:] = direction.x.array
    out["total"] = out["membrane"] + out["bending"] + out["shear"]
    return out


def tape_linear(
    config: Config,
    resolution: MeshResolution,
    technology: str = "psri",
    comm=MPI.COMM_WORLD,
    rotation: float = 1e-4,
) -> CaseResult:
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
    model = NaghdiShell(strip, ShellMaterial(tp.E, tp.nu, tp.h), technology, director_frame="global")
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
    solver = SNESSolver.from_config(
        F,
        model.jacobian_form(F),
        model.q,
        root.bcs,
        config.solver,
        prefix="verify_tape_linear_",
        snes_type="ksponly",
    )
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
            "dofs": global_size(model.W),
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
        F, model.jacobian_form(F), model.q, root.bcs, settings, prefix=_prefix("rollup")
    )
    control = settings.control(initial_step=0.05, max_step=0.1, min_step=1e-6)
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


def stress_free(config: Config, resolution: MeshResolution, comm=MPI.COMM_WORLD) -> CaseResult:
    """The benchmark tape in its reference configuration carries no strain and no residual.

    Checks: strain energy below 1e-12 J and the residual at round-off, below 1e-12 of the
    residual that a unit rotation of the free end would cause (the scale of the forces the
    discretisation can represent).
    """
    tp = config.tape
    strip = create_strip_mesh(comm, StripGeometry.from_config(config), resolution)
    model = NaghdiShell(strip, ShellMaterial(tp.E, tp.nu, tp.h), director_frame="global")
    energy = energies(model)["total"]
    F0 = dolfinx.fem.form(model.residual())

    def residual_norm() -> float:
        b = dolfinx.fem.petsc.assemble_vector(F0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        norm = b.norm()
        b.destroy()
        return norm

    r0 = residual_norm()
    # scale: the residual of the reference state with the free end turned by 1 rad rigidly
    end = EdgeMotion(model, FREE_END, axis=np.array([0.0, 1.0, 0.0]), axis_point=np.array([tp.L, 0.0, 0.0]))
    end.set(1.0)
    model.q.x.array[:] = 0.0
    for bc in end.bcs:
        bc.set(model.q.x.array)
    model.q.x.scatter_forward()
    scale = residual_norm()
    return CaseResult(
        "stress-free",
        [
            Check("reference strain energy [J]", energy, 0.0, 1e-12, True),
            Check("reference residual / residual scale", r0 / scale, 0.0, 1e-12, True),
        ],
        {"mesh": f"{resolution.along} x {resolution.across}", "residual_norm": r0, "residual_scale": scale},
    )


# the mesh preset of a case when none is asked for: the coarsest that passes. The tape fold's
# radius R = 15 mm needs the default 4 mm elements: on the coarse 12.5 mm ones the fold's
# energy density misses mu by more than the 5 % tolerance
DEFAULT_PRESETS = {"tape-fold": "default"}


def _prefix(name: str) -> str:
    """The PETSc options prefix of a case's solver: -verify_tape_fold_snes_monitor."""
    return f"verify_{name.replace('-', '_')}_"


def run_case(name: str, config: Config, preset: str | None = None, comm=MPI.COMM_WORLD) -> CaseResult:
    """Run the verification case ``name`` on the mesh preset ``preset`` (collective).

    ``preset`` None: the case's own default (:data:`DEFAULT_PRESETS`, else coarse). The tape
    cases take the tape of ``config``, and every case with a solve its ``[solver]`` settings.
    """
    from tapecoil.config import MeshConfig

    if name not in CASES:
        raise ValueError(f"unknown verification case {name!r} (known: {', '.join(CASES)})")
    preset = preset or DEFAULT_PRESETS.get(name, "coarse")
    tape_res = MeshResolution.from_config(MeshConfig(preset=preset), config.tape.L)
    if name == "stress-free":
        result = stress_free(config, tape_res, comm)
    elif name == "tape-linear":
        result = tape_linear(config, tape_res, comm=comm)
    elif name == "rollup":
        result = rollup(ROLLUP_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "semicylinder":
        result = semicylinder(SEMICYLINDER_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "slit-plate":
        result = slit_plate(SLIT_PLATE_MESHES[preset], comm=comm, solver_config=config.solver)
    else:
        result = tape_fold(config, tape_res, comm=comm)
    result.info["preset"] = preset
    return result


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


def _solve_to_full_load(model, F, bcs, set_load, settings, prefix, steps, point_forces=()):
    """Newton with adaptive load stepping from 0 to the full load; returns the step history.

    ``settings``: the ``[solver]`` section; ``steps``: (first, largest) step as fractions of the load.
    """
    from tapecoil.core.stepping import Continuation

    solver = SNESSolver.from_config(F, model.jacobian_form(F), model.q, bcs, settings, prefix=prefix)
    control = settings.control(initial_step=steps[0], max_step=steps[1], min_step=1e-6)
    solver.point_forces.extend(point_forces)
    history = Continuation(solver.solve, set_load, model.q, control).run(0.0, 1.0)
    solver.destroy()
    return history


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
    history = _solve_to_full_load(
        model,
        model.residual(),
        bcs,
        lambda t: setattr(load, "value", t * P),
        solver_config or SolverConfig(),
        _prefix("semicylinder"),
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
    history = _solve_to_full_load(
        model,
        model.residual(work),
        clamp(model, ROOT).bcs,
        lambda t: setattr(line_force, "value", t * p_max),
        solver_config or SolverConfig(),
        _prefix("slit-plate"),
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


def _region_energy_density(model: NaghdiShell, V0, mask: np.ndarray) -> float:
    """Strain energy per unit area [J/m^2] over the owned cells flagged in ``mask`` (collective).

    The energy forms of the solve (same quadrature, PSRI included), weighted by the region's
    indicator, divided by the region's area.
    """
    chi = dolfinx.fem.Function(V0)
    chi.x.array[: len(mask)] = mask.astype(float)
    chi.x.scatter_forward()
    energy = sum(global_scalar(f, model.mesh.comm) for f in model.energy_forms(chi))
    return energy / global_scalar(chi * model.jacobian * model.dx, model.mesh.comm)


def tape_fold(
    config: Config,
    resolution: MeshResolution | None = None,
    length: float | None = None,
    final_angle: float = math.pi,
    comm=MPI.COMM_WORLD,
    on_step=None,
    snapshots: str | None = None,
) -> CaseResult:
    """Opposite-sense folding of the benchmark tape by turning its free end (Seffen and Pellegrino 1999).

    The benchmark tape (or a ``length`` piece of it), clamped at the root; the free end turned rigidly
    about the width axis (free to translate, so the load is a pure moment) in the opposite sense,
    through the snap where the section flattens, until a localised fold has formed and grown to
    ``final_angle``. Checks: the moment plateau after the snap against (1 + nu) D alpha (5 %), the
    fold's longitudinal radius against R (10 %), its flattened section, and the energy per unit
    area in the fold against mu (5 %). The tape must be long enough for the fold and its two
    transition zones to stay clear of the ends: on 0.2 m the moment rose again beyond 2.5 rad.
    ``snapshots``: a VTX path to write the shell at every step (ParaView).
    """
    from tapecoil.core.stepping import Continuation, Relaxation
    from tapecoil.models.edges import RigidSection

    tp = config.tape
    length = length or tp.L
    geom = StripGeometry(tp.R, tp.b, length)
    res = resolution or MeshResolution(across=9, along=round(length / 0.004))
    strip = create_strip_mesh(comm, geom, res)
    model = NaghdiShell(strip, ShellMaterial(tp.E, tp.nu, tp.h), director_frame="global")
    root = clamp(model, ROOT)
    end = RigidSection(model, FREE_END, axis=np.array([0.0, 1.0, 0.0]), stiffness=100 * tp.E * tp.h)
    h_e = length / res.along
    c, previous, viscous = model.relaxation(length_scale=h_e)
    total_energy = model.strain_energy + end.energy
    F = ufl.derivative(total_energy, model.q, model.dq) + viscous
    # small steps towards the snap (1 % to 2 % of the end rotation), and few cut-backs before
    # relaxing through it, unless [solver] sets its own; tolerances and PETSc options from it
    control = config.solver.control(initial_step=0.01, max_step=0.02, min_step=1e-4, max_cutbacks=4)
    solver = SNESSolver.from_config(
        F, model.jacobian_form(F), model.q, root.bcs + end.bcs, config.solver, prefix=_prefix("tape-fold")
    )
    energy_form = dolfinx.fem.form(total_energy)
    path = []
    writer = None
    if snapshots is not None:
        from tapecoil.core.output import ShellWriter

        writer = ShellWriter(model, snapshots)
        writer.write(0.0)

    def record(step):
        energy = global_scalar(energy_form, model.mesh.comm)
        path.append((end.angle, energy, step.iterations, step.relaxed))
        if writer is not None:
            writer.write(end.angle)
        if on_step is not None:
            on_step(step, end.angle, energy)

    D = tp.D
    relax = Relaxation(c, previous, scale=10 * D / h_e**4)
    t0 = time.perf_counter()
    try:
        Continuation(solver.solve, end.set, model.q, control, relaxation=relax, on_step=record).run(
            0.0, final_angle
        )
    finally:
        if writer is not None:
            writer.close()
    wall = time.perf_counter() - t0
    timing = solver.timing_per_iteration()
    solver.destroy()

    phi, energy = np.array([p[0] for p in path]), np.array([p[1] for p in path])
    # the snap: under rotation control the energy can only fall through a dynamic jump (with or
    # without relaxation, the first step whose energy is below its predecessor's)
    snap = next((i for i in range(1, len(path)) if energy[i] < energy[i - 1] or path[i][3]), None)
    # M = dE/dphi on each branch: the energy drops across the snap, which has no derivative
    branches = [slice(0, snap), slice(snap, None)] if snap is not None else [slice(None)]
    moment = np.concatenate(
        [
            np.gradient(energy[b], phi[b]) if len(phi[b]) > 1 else np.full(len(phi[b]), np.nan)
            for b in branches
        ]
    )
    M_star = theory.fold_moment(D, tp.nu, tp.alpha)
    # plateau: the secant slope of the energy over the second half of the post-snap path
    if snap is not None:
        first = snap + (len(phi) - snap) // 2
        plateau = (energy[-1] - energy[first]) / (phi[-1] - phi[first])
    else:
        plateau = float("nan")

    kx, ky = model.curvatures()
    V0, local = cell_midpoint_values(model.mesh, [kx, ky])
    cells = np.vstack(comm.allgather(local))
    # opposite sense: the fold's longitudinal curvature is negative (the section's own is +1/R)
    inner = np.abs(cells[:, 1]) <= 0.3 * tp.b  # inner 60 % of the width
    bend = -cells[:, 2]
    threshold = 0.7 * np.max(bend[inner])
    fold = inner & (bend > threshold)
    local_fold = (np.abs(local[:, 1]) <= 0.3 * tp.b) & (-local[:, 2] > threshold)
    fold_radius = float(np.median(1.0 / bend[fold])) if fold.any() else float("nan")
    transverse = float(np.median(np.abs(cells[fold, 3]))) * tp.R if fold.any() else float("nan")
    w_fold = _region_energy_density(model, V0, local_fold) if fold.any() else float("nan")
    return CaseResult(
        "tape-fold",
        [
            Check("moment plateau / (1 + nu) D alpha", plateau / M_star, 1.0, 0.05),
            Check("fold radius / R", fold_radius / tp.R, 1.0, 0.10),
            Check("transverse curvature in the fold x R", transverse, 0.0, 0.10, True),
            Check("energy density in the fold / mu", w_fold / tp.mu, 1.0, 0.05),
        ],
        {
            "mesh": f"{res.along} x {res.across}",
            "dofs": global_size(model.W),
            "length": length,
            "steps": len(path),
            "snap_angle": float(phi[snap]) if snap is not None else None,
            "peak_moment": float(np.nanmax(moment)),
            "plateau_moment": plateau,
            "fold_cells": int(fold.sum()),
            "fold_x_range": [float(cells[fold, 0].min()), float(cells[fold, 0].max())]
            if fold.any()
            else None,
            "path": [[float(a), float(m)] for a, m in zip(phi, moment, strict=True)],
            "newton_iterations": [p[2] for p in path],
            "wall_time": wall,
            "time_per_iteration": timing,
        },
        model=model,
    )
