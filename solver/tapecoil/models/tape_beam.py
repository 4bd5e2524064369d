"""The tape as a beam beside a shell window: the arc section's line, and the flattened strip
before the window (:func:`tape_beam`), as the hybrid's coiling and its verification build it."""

from __future__ import annotations

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.models.beam_problem import BeamProblem
from tapecoil.models.beam_section import BeamSection

__all__ = ["section_frame", "tape_beam"]


def section_frame(x: np.ndarray) -> np.ndarray:
    """The beam's frame along a straight tape: along x, the chord (y), towards the centre (z)."""
    return np.broadcast_to(np.eye(3), (x.shape[1], 3, 3))


def tape_beam(
    config,
    spans: list[tuple[float, float]],
    element: float,
    *,
    flat_before: float = 0.0,
    edge_relief: bool = False,
    comm=MPI.COMM_WORLD,
    name: str = "beam",
) -> BeamProblem:
    """The tape of ``config`` (an isotropic wall) as a beam on ``spans`` [(s0, s1), ...] [m] of
    its length, elements ``element`` [m] long, its line along x at the arc's centroid: the arc
    section (:meth:`BeamSection.circular_arc`), and before ``flat_before`` [m] the flattened
    strip (:meth:`BeamSection.flattened_strip`; with ``edge_relief`` the coil's free edges'
    relief in its energy). No supports or loads."""
    if config.laminate.kind != "isotropic":
        raise ValueError(
            "the hybrid's beam takes an isotropic arc section: [laminate] kind must be isotropic"
        )
    tp = config.tape
    centroid = BeamSection.arc_centroid_depth(tp.R, tp.alpha)
    beam = BeamProblem(
        lambda s: np.column_stack([s, 0 * s, 0 * s + centroid]),
        spans,
        [max(1, round((b - a) / element)) for a, b in spans],
        BeamSection.circular_arc(tp.R, tp.alpha, tp.h, tp.E, tp.nu),
        section_frame,
        comm=comm,
        name=name,
    )
    if flat_before > 0:
        D = tp.E * tp.h**3 / (12 * (1 - tp.nu**2))
        stiffness = config.wall.axial_stiffness if edge_relief else None
        flat = BeamSection.flattened_strip(
            D, tp.nu * D, D, tp.R, tp.b, tp.h, tp.E, tp.nu, axial_stiffness=stiffness
        )
        owned = np.arange(beam.mesh.topology.index_map(1).size_local, dtype=np.int32)
        middle = dolfinx.mesh.compute_midpoints(beam.mesh, 1, owned)[:, 0]
        beam.model.set_section(owned[middle < flat_before], flat)
    return beam
