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
from tapecoil.models.beam_problem import BeamProblem
from tapecoil.models.beam_section import BeamSection
from tapecoil.models.hybrid_problem import HybridProblem
from tapecoil.models.materials import ShellMaterial
from tapecoil.verification.checks import CaseResult, Check

CANTILEVER_LENGTH = 0.3  # [m]
WINDOW = 0.1  # [m] of shell at the root
TIP_ROTATION = 1e-4  # [rad] by beam theory: a linear response
PENALTY = 1e3


def _section_frame(x: np.ndarray) -> np.ndarray:
    """The beam's frame along a straight tape: along x, the chord (y), towards the centre (z)."""
    return np.broadcast_to(np.eye(3), (x.shape[1], 3, 3))


def hybrid_cantilever_problem(
    config: Config,
    resolution: MeshResolution,
    window: float,
    *,
    penalty=PENALTY,
    comm=MPI.COMM_WORLD,
    name="verify_hybrid",
):
    """The tape of ``config`` as a cantilever of :data:`CANTILEVER_LENGTH`: a shell of ``window``
    [m] clamped at the root, tied to a beam on the rest; ``resolution``: the shell's elements
    across and its element length (``along`` elements per :data:`CANTILEVER_LENGTH`), the beam
    with elements of that length. Returns (hybrid, tip point of the beam)."""
    from tapecoil.models.problem import ShellProblem

    tp = config.tape
    size = CANTILEVER_LENGTH / resolution.along
    centroid = BeamSection.arc_centroid_depth(tp.R, tp.alpha)
    shell = ShellProblem(
        StripGeometry(tp.R, tp.b, window),
        MeshResolution(resolution.across, max(1, round(window / size))),
        ShellMaterial(tp.E, tp.nu, tp.h),
        comm=comm,
        director_frame="global",
        name=f"{name}_shell",
    )
    rest = CANTILEVER_LENGTH - window
    beam = BeamProblem(
        lambda s: np.column_stack([window + s, 0 * s, 0 * s + centroid]),
        rest,
        max(1, round(rest / size)),
        BeamSection.circular_arc(tp.R, tp.alpha, tp.h, tp.E, tp.nu),
        _section_frame,
        comm=comm,
        name=f"{name}_beam",
    )
    hybrid = HybridProblem(shell, beam, (window, 0.0, centroid), modulus=tp.E, penalty=penalty, name=name)
    return hybrid, (CANTILEVER_LENGTH, 0.0, centroid)


def _tip_deflection(config, resolution, window, force, penalty, comm) -> tuple[float, HybridProblem, float]:
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
    force = TIP_ROTATION * 2 * EI / L**2
    element = L / resolution.along
    hybrid_tip, hybrid, hybrid_wall = _tip_deflection(config, resolution, WINDOW, force, PENALTY, comm)
    gaps = hybrid.tie.gaps()
    stiffer, _, _ = _tip_deflection(config, resolution, WINDOW, force, 10 * PENALTY, comm)
    shell_tip, full, shell_wall = _tip_deflection(config, resolution, L - element, force, PENALTY, comm)

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
