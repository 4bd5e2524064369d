"""Verification of the shell-beam hybrid (:mod:`tapecoil.models.hybrid_problem`).

``hybrid-cantilever``: the benchmark tape's section as a 0.3 m cantilever, clamped at the root,
a shell over its first 0.1 m and a beam of the arc section (:meth:`BeamSection.circular_arc`)
beyond, the two tied as a rigid section.

- A small transverse force at the tip (an end rotation of 1e-4 rad by beam theory), in the
  plane of symmetry. The reference is the full shell of the same mesh whose end section is tied
  to a one-element beam that carries the force: the same end condition, with shell in place of
  beam over the middle 0.19 m. (A force spread over a free end flattens the section there: that
  tape is 2 % more compliant than either, a local effect of how the load is applied.) The
  deflection of the hybrid's tip must match the full shell's within 1 %, the accuracy the
  hybrid is meant to keep; it is about 0.3 % on every mesh preset.
- The penalty converged: the tip deflection with ten times the penalty factor moves by less
  than 1e-4 of itself.
- A rigid turn (consistency): the clamp turned by one full turn about the width axis, no load.
  The hybrid must turn as a rigid body: its tip back at its place to 1e-9 of the length, its
  strain energy at round-off. This exercises the tie's incremental rotations (moved on at
  every accepted step) through a whole turn.

``hybrid-fold``: the tape of ``tape-fold`` (the benchmark's 0.5 m) with shell over its first
:data:`FOLD_WINDOW` and the arc-section beam beyond, its end turned about the width axis in the
opposite sense (free to translate: a pure moment) to pi. The shell must fold where the beam
cannot, and the moment, carried by the beam and passed through the tie, must settle on the
plateau of an opposite-sense fold: against alpha (sqrt(D11 D22) + D12) within 5 %, the fold's
radius against R sqrt(D11 / D22) within 10 % and its section flat, as ``tape-fold`` checks the
full shell (physics brief Sec. 10); and side by side with the full shell (``tape-fold`` on the
same mesh), the plateau and the fold's radius within 2 %. Through the snap the shell is
relaxed (pseudo-transient), as in ``tape-fold``.
"""

from __future__ import annotations

import math
import time

import numpy as np
from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import Config
from tapecoil.core.dofs import global_scalar, global_size
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.beam_section import BeamSection
from tapecoil.models.hybrid_problem import HybridProblem
from tapecoil.models.materials import ShellMaterial
from tapecoil.models.solver_terms import relaxation_scale
from tapecoil.models.tape_beam import tape_beam
from tapecoil.verification.checks import CaseResult, Check

CANTILEVER_LENGTH = 0.3  # [m]
WINDOW = 0.1  # [m] of shell at the root
TIP_ROTATION = 1e-4  # [rad] by beam theory: a linear response
PENALTY = 1e3
# [m] of shell at the root of the folded tape: room for the fold grown to pi and its transitions
# (a shorter window raises the plateau above the full shell's, the fold feeling its ends)
FOLD_WINDOW = 0.3


def tape_hybrid(
    config: Config,
    across: int,
    element: float,
    length: float,
    window: float,
    *,
    start: float = 0.0,
    flat_root: bool = False,
    edge_relief: bool = False,
    penalty=PENALTY,
    comm=MPI.COMM_WORLD,
    name="verify_hybrid",
):
    """The tape of ``config`` (an isotropic wall), ``length`` [m] long, as a hybrid: a shell of
    ``window`` [m] from ``start`` [m], ``across`` elements across and ``element`` [m] long, tied
    to a beam of the arc section on the rest (on both sides when ``start`` > 0), its elements as
    long; with ``flat_root``, the beam before the window is of the flattened strip's section
    and tied flat (:meth:`HybridProblem.flatten` flattens it by steps), with ``edge_relief`` the
    free edges' relief of a coil in its energy (:meth:`BeamSection.flattened_strip`; for a coil,
    not a straight flattened end). No supports or loads yet.
    Returns (hybrid, the tape's tip [m], a beam node unless the window reaches it)."""
    from tapecoil.models.problem import ShellProblem

    tp = config.tape
    centroid = BeamSection.arc_centroid_depth(tp.R, tp.alpha)
    shell = ShellProblem(
        StripGeometry(tp.R, tp.b, window, start=start),
        MeshResolution(across, max(1, round(window / element))),
        ShellMaterial(tp.E, tp.nu, tp.h),
        comm=comm,
        director_frame="global",
        name=f"{name}_shell",
    )
    end = start + window
    to_the_end = end >= length - 1e-9 * length
    spans = ([(0.0, start)] if start > 0 else []) + ([] if to_the_end else [(end, length)])
    if not spans:
        raise ValueError("tape_hybrid: the window covers the whole tape; that is the full shell")
    beam = tape_beam(
        config,
        spans,
        element,
        flat_before=start if flat_root else 0.0,
        edge_relief=edge_relief,
        comm=comm,
        name=f"{name}_beam",
    )
    ties = [] if to_the_end else [("xi1_max", (end, 0.0, centroid), "arc")]
    if start > 0:
        ties.insert(0, ("xi1_min", (start, 0.0, centroid), "flat" if flat_root else "arc"))
    hybrid = HybridProblem(shell, beam, ties=ties, modulus=tp.E, penalty=penalty, name=name)
    return hybrid, (length, 0.0, centroid)


def hybrid_cantilever_problem(
    config: Config,
    resolution: MeshResolution,
    window: float,
    *,
    penalty=PENALTY,
    comm=MPI.COMM_WORLD,
    name="verify_hybrid",
):
    """:func:`tape_hybrid` of :data:`CANTILEVER_LENGTH`, ``resolution`` its elements across and
    along that length."""
    element = CANTILEVER_LENGTH / resolution.along
    return tape_hybrid(
        config, resolution.across, element, CANTILEVER_LENGTH, window, penalty=penalty, comm=comm, name=name
    )


def _tip_force(config: Config) -> float:
    """The tip force [N] that turns the cantilever's tip by TIP_ROTATION by beam theory."""
    tp = config.tape
    return TIP_ROTATION * 2 * tp.E * theory.arc_second_moment(tp.R, tp.alpha, tp.h) / CANTILEVER_LENGTH**2


def cantilever_tip_deflection(
    config: Config,
    resolution: MeshResolution,
    window: float = WINDOW,
    force: float | None = None,
    penalty: float = PENALTY,
    comm=MPI.COMM_WORLD,
) -> tuple[float, HybridProblem, float]:
    """The hybrid cantilever's tip deflection [m] under the tip ``force`` [N] (default: the
    case's, a linear response), with the problem and the solve's wall time [s]."""
    if force is None:
        force = _tip_force(config)
    hybrid, tip = hybrid_cantilever_problem(config, resolution, window, penalty=penalty, comm=comm)
    hybrid.shell.clamp("xi1_min")
    hybrid.beam.end_load(tip, force=(0.0, 0.0, 1.0))
    t0 = time.perf_counter()
    hybrid.solve(force, first_step=force, max_step=force, solver_config=config.solver)
    wall = time.perf_counter() - t0
    return float(hybrid.beam.position(tip)[2] - tip[2]), hybrid, wall


def hybrid_cantilever(config: Config, resolution: MeshResolution, comm=MPI.COMM_WORLD) -> CaseResult:
    """The hybrid cantilever against the full shell, and its rigid turn (see the module)."""
    tp = config.tape
    EI = tp.E * theory.arc_second_moment(tp.R, tp.alpha, tp.h)
    L = CANTILEVER_LENGTH
    force = _tip_force(config)
    element = L / resolution.along
    hybrid_tip, hybrid, hybrid_wall = cantilever_tip_deflection(
        config, resolution, WINDOW, force, PENALTY, comm
    )
    gaps = hybrid.ties["xi1_max"].gaps()
    stiffer, _, _ = cantilever_tip_deflection(config, resolution, WINDOW, force, 10 * PENALTY, comm)
    shell_tip, full, shell_wall = cantilever_tip_deflection(
        config, resolution, L - element, force, PENALTY, comm
    )

    turned, tip = hybrid_cantilever_problem(config, resolution, WINDOW, comm=comm, name="verify_hybrid_turn")
    turned.shell.turn("xi1_min", (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
    t0 = time.perf_counter()
    turned.solve(2 * math.pi, first_step=math.pi / 16, max_step=math.pi / 8, solver_config=config.solver)
    turn_wall = time.perf_counter() - t0
    tip_error = float(np.linalg.norm(turned.beam.position(tip) - np.asarray(tip))) / L
    energy = global_scalar(turned.shell.model.strain_energy, comm) + turned.beam.model.strain_energy()

    def dofs(h):
        return global_size(h.shell.model.W) + global_size(h.beam.model.W)

    return CaseResult(
        "hybrid-cantilever",
        [
            Check("tip deflection, hybrid / full shell", hybrid_tip / shell_tip, 1.0, 0.01),
            Check("tip deflection, penalty x 10 / penalty", stiffer / hybrid_tip, 1.0, 1e-4),
            Check("rigid turn: tip displacement / length", tip_error, 0.0, 1e-9, True),
            Check("rigid turn: strain energy [J]", energy, 0.0, 1e-12, True),
        ],
        {
            "mesh": f"{resolution.across} across, elements {element * 1e3:.3g} mm long",
            "window": WINDOW,
            "tip_force": force,
            "tip_deflection": {
                "hybrid": hybrid_tip,
                "full_shell": shell_tip,
                "beam_theory": force * L**3 / (3 * EI),
            },
            "tie_gap_rms": {"position": gaps[0], "director": gaps[1]},
            "dofs": {"hybrid": dofs(hybrid), "full_shell": dofs(full)},
            "wall_time": {"hybrid": hybrid_wall, "full_shell": shell_wall, "turn": turn_wall},
            "turn_steps": len(turned.history),
            "turn_newton_iterations": sum(r.iterations for r in turned.history),
        },
    )


def hybrid_fold(
    config: Config,
    resolution: MeshResolution,
    comm=MPI.COMM_WORLD,
    final_angle: float = math.pi,
    on_step=None,
) -> CaseResult:
    """The tape folded by its turned end, shell near the root and beam beyond (see the module).

    ``resolution``: the shell's elements across and along the tape's length (the beam's elements
    as long); ``on_step(record, angle, energy)`` after each accepted step."""
    from tapecoil.verification.tape import fold_shape, moment_path, tape_fold

    tp = config.tape
    element = tp.L / resolution.along
    hybrid, tip = tape_hybrid(
        config, resolution.across, element, tp.L, FOLD_WINDOW, comm=comm, name="verify_hybrid_fold"
    )
    hybrid.shell.clamp("xi1_min")
    hybrid.beam.turn(tip, (0.0, 1.0, 0.0))
    bending = config.wall.bending
    path = []

    def record(step):
        path.append((step.load, hybrid.energy(), step.iterations, step.relaxed))
        if on_step is not None:
            on_step(step, step.load, path[-1][1])

    # small steps towards the snap (1 % to 2 % of the end rotation) and few cut-backs before
    # relaxing through it, as tape-fold
    hybrid.solve(
        final_angle,
        first_step=0.01 * final_angle,
        max_step=0.02 * final_angle,
        max_cutbacks=4,
        relaxation=relaxation_scale(bending, element),
        on_step=record,
        solver_config=config.solver,
    )
    phi, energy = np.array([p[0] for p in path]), np.array([p[1] for p in path])
    snap, moment, plateau = moment_path(phi, energy, [p[3] for p in path])
    shape = fold_shape(hybrid.shell.model, tp.b, tp.R)
    fold_reference = theory.fold_radius(bending, tp.R)
    dofs = global_size(hybrid.shell.model.W) + global_size(hybrid.beam.model.W)
    full = tape_fold(config, resolution, final_angle=final_angle, comm=comm)
    full_radius = full.checks[1].computed * fold_reference
    return CaseResult(
        "hybrid-fold",
        [
            Check(
                "moment plateau / alpha (sqrt(D11 D22) + D12)",
                plateau / theory.fold_moment(bending, tp.alpha),
                1.0,
                0.05,
            ),
            Check("fold radius / R sqrt(D11 / D22)", shape["radius"] / fold_reference, 1.0, 0.10),
            Check("transverse curvature in the fold x R", shape["transverse"], 0.0, 0.10, True),
            Check("moment plateau / the full shell's", plateau / full.info["plateau_moment"], 1.0, 0.02),
            Check("fold radius / the full shell's", shape["radius"] / full_radius, 1.0, 0.02),
        ],
        {
            "mesh": f"shell {resolution.across} across, elements {element * 1e3:.3g} mm long",
            "window": FOLD_WINDOW,
            "dofs": {"hybrid": dofs, "full_shell": full.info["dofs"]},
            "steps": {"hybrid": len(path), "full_shell": full.info["steps"]},
            "newton_iterations": {
                "hybrid": int(sum(p[2] for p in path)),
                "full_shell": int(sum(full.info["newton_iterations"])),
            },
            "snap_angle": float(phi[snap]) if snap is not None else None,
            "peak_moment": float(np.nanmax(moment)),
            "plateau_moment": plateau,
            "fold_x_range": shape["x_range"],
            "fold_energy_density_over_mu": shape["energy_density"]
            / theory.energy_density(fold_reference, tp.R, bending),
            "tie_gap_rms": dict(zip(("position", "director"), hybrid.ties["xi1_max"].gaps(), strict=True)),
            "wall_time": {"hybrid": hybrid.wall_time, "full_shell": full.info["wall_time"]},
            "full_shell_snap_angle": full.info["snap_angle"],
            "path": [[float(a), float(m)] for a, m in zip(phi, moment, strict=True)],
        },
        model=hybrid.shell.model,
    )


def coiled_shell_fit(
    config: Config, *, ratio: float | None = None, edge_relief: bool = False, comm=MPI.COMM_WORLD
) -> tuple[float, float, float, float, float, float]:
    """The tape of ``config`` on a hub of radius ``ratio`` R (``config``'s hub when None), 0.12 m
    of it coiled by 3 rad as a full shell (default mesh, the pull Eq. 2.6 + 0.3 N), then turned
    into a hybrid (:func:`tapecoil.models.window.full_shell`): a beam of the flattened strip's
    section up to 2.4 rad of winding (with ``edge_relief``, the free edges' relief in its
    energy), tied flat to the shell beyond. Returns the energies per unit length [J/m] of the
    shell's coil and of the beam over whole elements from 1 to 2 rad of winding, the beam's
    curvature there times rho, the ties' energy [J], and the plate's energy per unit length
    b w(rho) and the edges' relief [J/m] (collective)."""
    import dataclasses

    import ufl

    from tapecoil.models.window import carry_over, full_shell
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    tp, wall = config.tape, config.wall
    r_c = config.hub.radius if ratio is None else ratio * tp.R
    rho = r_c + tp.h / 2
    pull = theory.coiling_tension_bending(wall.bending, tp.alpha, tp.R, r_c) + 0.3
    case = dataclasses.replace(
        config,
        tape=dataclasses.replace(tp, L=0.12),
        hub=dataclasses.replace(config.hub, radius=r_c),
        coiling=dataclasses.replace(config.coiling, hub_angle=3.0, tension=pull),
        mesh=dataclasses.replace(config.mesh, preset="default"),
        contact=dataclasses.replace(config.contact, smoothing=0.0),
    )
    model = CoilingProblem(case, comm)
    run = CoilingRun(model)
    run.flatten()
    run.coil(3.0)
    shell = model.tape.model
    length, resolution = case.tape.L, model.tape.strip.resolution
    element = length / resolution.along
    start = round(2.4 * rho / element) * element
    hybrid, _ = tape_hybrid(
        case,
        resolution.across,
        element,
        length,
        length - start,
        start=start,
        flat_root=True,
        edge_relief=edge_relief,
        comm=comm,
    )
    carry_over(full_shell(shell), hybrid)
    model.solver.destroy()
    s1, s2 = (round(angle * rho / element) * element for angle in (1.0, 2.0))

    def per_length(mesh):
        x = ufl.SpatialCoordinate(mesh)[0]
        return ufl.conditional(ufl.And(ufl.ge(x, s1), ufl.le(x, s2)), 1.0, 0.0) / (s2 - s1)

    beam = hybrid.beam.model
    shell_energy = sum(global_scalar(form, comm) for form in shell.energy_forms(per_length(shell.mesh)))
    weight = per_length(beam.mesh)
    beam_energy = global_scalar(weight * beam.energy_density * beam.dx, comm)
    curvature = global_scalar(weight * (beam.curvature[1] - beam.curvature_0[1]) * beam.dx, comm)
    plate = tp.b * theory.energy_density(rho, tp.R, wall.bending)
    relief = theory.edge_layer(wall.bending, wall.axial_stiffness, tp.R, rho).energy_relief
    return shell_energy, beam_energy, curvature * rho, hybrid.coupling.energy(), plate, relief


def moved_cantilever(config: Config, *, force: float = 0.5, direct: bool = True, comm=MPI.COMM_WORLD):
    """A cantilever of ``config``'s section (coarse mesh, 0.3 m, root clamped on the beam) with
    its shell window at 0.05-0.15 m, under a tip force stepped to ``force`` [N]; the window moved
    on to 0.1-0.2 m (the shell behind turned into beam, the beam ahead into shell) and stepped on
    by 5 %; with ``direct``, the run with the window at 0.1-0.2 m all along. Returns (moved,
    direct or None, tip, energies before and after the move, the ties' energy after it)."""
    from tapecoil.models.window import carry_over

    def build(start, name):
        hybrid, tip = tape_hybrid(
            config, 4, 0.0125, CANTILEVER_LENGTH, 0.1, start=start, comm=comm, name=name
        )
        hybrid.beam.clamp((0.0, 0.0, tip[2]))
        hybrid.beam.end_load(tip, force=(0.0, 0.0, 1.0))
        return hybrid, tip

    old, tip = build(0.05, "moved_old")
    old.solve(force, first_step=force / 8, max_step=force / 8, solver_config=config.solver)
    moved, _ = build(0.1, "moved")
    before = old.energy()
    carry_over(old, moved)
    after = moved.energy()
    ties = moved.coupling.energy()
    moved.solve(1.05 * force, first_step=0.05 * force, max_step=0.05 * force, solver_config=config.solver)
    if not direct:
        return moved, None, tip, (before, after), ties
    uninterrupted, _ = build(0.1, "moved_direct")
    uninterrupted.solve(1.05 * force, first_step=force / 8, max_step=force / 8, solver_config=config.solver)
    return moved, uninterrupted, tip, (before, after), ties


def hybrid_window(config: Config, comm=MPI.COMM_WORLD) -> CaseResult:
    """``hybrid-window``: the window moved and a coil turned into beam.

    - The window moved by 0.05 m along a loaded cantilever (:func:`moved_cantilever`): one step
      on, as the run that had the window there all along (tip to 2e-5 of L, energy to 1e-3);
      they differ by the new tie's kept shape, the shell's section as it was.
    - A coil of ``config``'s tape on its hub, as a full shell, turned into a flattened-strip beam
      behind a window (:func:`coiled_shell_fit`): the beam reads the coil's curvature
      (consistency: the hub imposes it, 0.5 %); its energy per unit length is the plate's
      b w(rho) (0.5 %), above the shell's by the free edges' relief (its share of the shell's
      energy against theory.edge_layer's, 10 %); with the relief in its energy it holds the
      shell's (0.5 %).
    """
    t0 = time.perf_counter()
    moved, direct, tip, (before, after), ties = moved_cantilever(config, comm=comm)
    gap = float(np.linalg.norm(moved.beam.position(tip) - direct.beam.position(tip))) / CANTILEVER_LENGTH
    shell_energy, plate_beam, curvature, fit_ties, plate, relief = coiled_shell_fit(config, comm=comm)
    relieved_beam = coiled_shell_fit(config, edge_relief=True, comm=comm)[1]
    checks = [
        Check("moved window: tip's distance from the uninterrupted run's / L", gap, 0.0, 2e-5, absolute=True),
        Check("moved window: energy / the uninterrupted run's", moved.energy() / direct.energy(), 1.0, 1e-3),
        Check("coil fit: the beam's curvature x rho (consistency)", curvature, 1.0, 5e-3),
        Check("coil fit: the flattened beam's energy / the plate's b w(rho)", plate_beam / plate, 1.0, 5e-3),
        Check(
            "coil fit: (beam / shell - 1) / the edges' relief share",
            (plate_beam / shell_energy - 1) / (relief / (plate - relief)),
            1.0,
            0.1,
        ),
        Check(
            "coil fit: the beam with the edges' relief / the shell", relieved_beam / shell_energy, 1.0, 5e-3
        ),
    ]
    return CaseResult(
        "hybrid-window",
        checks,
        {
            "preset": "coarse and default",
            "mesh": "the cantilever 4 x 24 elements, the coil 9 x 30",
            "energy_change_at_the_move": after / before - 1,
            "ties_energy_after_the_move": ties,
            "coil_energy_per_length": {
                "shell": shell_energy,
                "beam": plate_beam,
                "beam_with_edges": relieved_beam,
                "plate": plate,
                "plate_less_edges": plate - relief,
            },
            "coil_fit_ties_energy": fit_ties,
            "wall_time": time.perf_counter() - t0,
        },
    )
