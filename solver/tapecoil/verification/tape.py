"""Verification on the benchmark tape itself: the stress-free reference state, the linear end
moment against beam theory, and the fold through the snap to the Wuest moment."""

from __future__ import annotations

import math
import time

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil import theory
from tapecoil.config import Config
from tapecoil.core import jit
from tapecoil.core.dofs import cell_midpoint_values, global_scalar, global_size
from tapecoil.core.newton import SNESSolver
from tapecoil.geometry.meshes import FREE_END, ROOT, MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.edges import EdgeMotion, clamp
from tapecoil.models.shell import NaghdiShell, shell_material
from tapecoil.models.solver_terms import relaxation_scale
from tapecoil.verification.checks import (
    CaseResult,
    Check,
    edge_integral,
    energies,
    quadratic_energies,
    region_energy_density,
    solver_prefix,
)


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
    model = NaghdiShell(strip, shell_material(config), technology, director_frame="global")
    I = theory.arc_second_moment(tp.R, tp.alpha, tp.h)
    E_axial = config.wall.axial_modulus
    M = rotation * E_axial * I / tp.L
    beta = tp.alpha / 2
    z_c = tp.R * (1 - math.sin(beta) / beta)  # centroid of the arc
    z = model.phi0[2]
    I_membrane = edge_integral(model, tp.h * (z - z_c) ** 2, FREE_END)
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
    W = edge_integral(model, ufl.dot(traction, model.u), FREE_END)
    E = quadratic_energies(model)
    phi = W / M
    phi_beam = M * tp.L / (E_axial * I)
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


def stress_free(config: Config, resolution: MeshResolution, comm=MPI.COMM_WORLD) -> CaseResult:
    """The benchmark tape in its reference configuration carries no strain and no residual.

    Checks: strain energy below 1e-12 J and the residual at round-off, below 1e-12 of the
    residual that a unit rotation of the free end would cause (the scale of the forces the
    discretisation can represent).
    """
    tp = config.tape
    strip = create_strip_mesh(comm, StripGeometry.from_config(config), resolution)
    model = NaghdiShell(strip, shell_material(config), director_frame="global")
    energy = energies(model)["total"]
    F0 = jit.form(model.residual())

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


def tape_fold(
    config: Config,
    resolution: MeshResolution | None = None,
    length: float | None = None,
    final_angle: float = math.pi,
    comm=MPI.COMM_WORLD,
    on_step=None,
    snapshots: str | None = None,
) -> CaseResult:
    """Opposite-sense folding of the configured tape by turning its free end (Seffen and Pellegrino 1999).

    The tape (the benchmark's by default, or a ``length`` piece of it; any wall, a laminate's
    too), clamped at the root; the free end turned rigidly about the width axis (free to
    translate, so the load is a pure moment) in the opposite sense, through the snap where the
    section flattens, until a localised fold has formed and grown to ``final_angle``. Checks:
    the moment plateau after the snap against alpha (sqrt(D11 D22) + D12) ((1 + nu) D alpha for
    an isotropic wall; 5 %), the fold's longitudinal radius against R sqrt(D11 / D22) (R; 10 %),
    its flattened section, and the energy per unit area in the fold against the plate's w at
    that radius (mu; 5 %), physics brief Sec. 10. The tape must be long enough for the fold and
    its two transition zones to stay clear of the ends: on 0.2 m the moment rose again beyond 2.5 rad.
    ``snapshots``: a VTX path to write the shell at every step (ParaView).
    """
    from tapecoil.core.stepping import Continuation, Relaxation
    from tapecoil.models.edges import RigidSection

    tp = config.tape
    length = length or tp.L
    geom = StripGeometry(tp.R, tp.b, length)
    res = resolution or MeshResolution(across=9, along=round(length / 0.004))
    strip = create_strip_mesh(comm, geom, res)
    model = NaghdiShell(strip, shell_material(config), director_frame="global")
    root = clamp(model, ROOT)
    end = RigidSection(
        model, FREE_END, axis=np.array([0.0, 1.0, 0.0]), stiffness=100 * config.wall.axial_modulus * tp.h
    )
    h_e = length / res.along
    c, previous, viscous = model.relaxation(length_scale=h_e)
    total_energy = model.strain_energy + end.energy
    F = ufl.derivative(total_energy, model.q, model.dq) + viscous
    # small steps towards the snap (1 % to 2 % of the end rotation), and few cut-backs before
    # relaxing through it, unless [solver] sets its own; tolerances and PETSc options from it
    control = config.solver.control(initial_step=0.01, max_step=0.02, min_step=1e-4, max_cutbacks=4)
    solver = SNESSolver.from_config(
        F,
        model.jacobian_form(F),
        model.q,
        root.bcs + end.bcs,
        config.solver,
        prefix=solver_prefix("tape-fold"),
        state_scale=model.rounding_scale(),
    )
    energy_form = jit.form(total_energy)
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

    bending = config.wall.bending
    relax = Relaxation(c, previous, scale=relaxation_scale(bending, h_e))
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
    snap, moment, plateau = moment_path(phi, energy, [p[3] for p in path])
    M_star = theory.fold_moment(bending, tp.alpha)
    fold_reference = theory.fold_radius(bending, tp.R)
    w_reference = theory.energy_density(fold_reference, tp.R, bending)
    shape = fold_shape(model, tp.b, tp.R)
    fold_radius, transverse, w_fold = shape["radius"], shape["transverse"], shape["energy_density"]
    return CaseResult(
        "tape-fold",
        [
            Check("moment plateau / alpha (sqrt(D11 D22) + D12)", plateau / M_star, 1.0, 0.05),
            Check("fold radius / R sqrt(D11 / D22)", fold_radius / fold_reference, 1.0, 0.10),
            Check("transverse curvature in the fold x R", transverse, 0.0, 0.10, True),
            Check("energy density in the fold / w(fold radius)", w_fold / w_reference, 1.0, 0.05),
        ],
        {
            "mesh": f"{res.along} x {res.across}",
            "dofs": global_size(model.W),
            "length": length,
            "steps": len(path),
            "snap_angle": float(phi[snap]) if snap is not None else None,
            "peak_moment": float(np.nanmax(moment)),
            "plateau_moment": plateau,
            "fold_cells": shape["cells"],
            "fold_x_range": shape["x_range"],
            "path": [[float(a), float(m)] for a, m in zip(phi, moment, strict=True)],
            "newton_iterations": [p[2] for p in path],
            "wall_time": wall,
            "time_per_iteration": timing,
        },
        model=model,
    )


def moment_path(phi: np.ndarray, energy: np.ndarray, relaxed) -> tuple:
    """The moment M = dE/dphi along a rotation-controlled fold's path: (index of the snap or
    None, M at every step, the plateau after the snap).

    The snap: under rotation control the energy can only fall through a dynamic jump (with or
    without relaxation, the first step whose energy is below its predecessor's). M is taken on
    each branch (the energy drops across the snap, which has no derivative); the plateau is
    the secant slope of the energy over the second half of the post-snap path.
    """
    snap = next((i for i in range(1, len(phi)) if energy[i] < energy[i - 1] or relaxed[i]), None)
    branches = [slice(0, snap), slice(snap, None)] if snap is not None else [slice(None)]
    moment = np.concatenate(
        [
            np.gradient(energy[b], phi[b]) if len(phi[b]) > 1 else np.full(len(phi[b]), np.nan)
            for b in branches
        ]
    )
    if snap is None:
        return None, moment, float("nan")
    first = snap + (len(phi) - snap) // 2
    return snap, moment, float((energy[-1] - energy[first]) / (phi[-1] - phi[first]))


def fold_shape(model: NaghdiShell, width: float, R: float) -> dict:
    """An opposite-sense fold in the shell ``model`` (a tape of arc ``width`` and radius ``R``
    [m]): the cells over the inner 60 % of the width whose longitudinal curvature is beyond 0.7
    of the largest; their median radius [m], median transverse curvature times R, energy per
    unit area [J/m^2], count and x range [m] (collective; NaN and None without a fold)."""
    comm = model.mesh.comm
    kx, ky = model.curvatures()
    V0, local = cell_midpoint_values(model.mesh, [kx, ky])
    cells = np.vstack(comm.allgather(local))
    # opposite sense: the fold's longitudinal curvature is negative (the section's own is +1/R)
    inner = np.abs(cells[:, 1]) <= 0.3 * width
    bend = -cells[:, 2]
    threshold = 0.7 * np.max(bend[inner])
    fold = inner & (bend > threshold)
    local_fold = (np.abs(local[:, 1]) <= 0.3 * width) & (-local[:, 2] > threshold)
    found = bool(fold.any())
    return {
        "radius": float(np.median(1.0 / bend[fold])) if found else float("nan"),
        "transverse": float(np.median(np.abs(cells[fold, 3]))) * R if found else float("nan"),
        "energy_density": region_energy_density(model, V0, local_fold) if found else float("nan"),
        "cells": int(fold.sum()),
        "x_range": [float(cells[fold, 0].min()), float(cells[fold, 0].max())] if found else None,
    }
