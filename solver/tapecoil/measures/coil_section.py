"""The coil's own sections on a stretch of steady coil: energy per unit length, the edges' lift
and the coiling tension read across them.

A flattened coil is where the plate laws of the physics brief hold, up to the free edges'
boundary layer (:mod:`tapecoil.theory.edge_layer`). These readings compare the shell with both,
away from the root (whose clamp holds the whole width flat) and from the lift-off (the ploy
region). Each is read from the state alone: the strain energy of the cells of the stretch, the
mid-surface's distance from the hub axis at the nodes, the force across the stretch's sections
(:mod:`tapecoil.measures.section_forces`); none from the contact that holds the tape.
"""

from __future__ import annotations

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.core import jit
from tapecoil.core.dofs import global_scalar
from tapecoil.measures.centre_line import edge_lines
from tapecoil.measures.section_forces import SectionForces


class CoilSection:
    """Readings over the stretch of a coil between two winding angles (collective).

    ``tape``: the :class:`~tapecoil.phases.tape_on_hub.TapeOnHub`. The energy forms are built
    once, with the stretch's material bounds as constants, so that a reading at another stretch
    compiles nothing.
    """

    def __init__(self, tape):
        self.tape = tape
        shell = tape.model
        self.bounds = (dolfinx.fem.Constant(shell.mesh, 0.0), dolfinx.fem.Constant(shell.mesh, 0.0))
        xi1 = ufl.SpatialCoordinate(shell.mesh)[0]
        inside = ufl.conditional(ufl.And(ufl.ge(xi1, self.bounds[0]), ufl.le(xi1, self.bounds[1])), 1.0, 0.0)
        self.energy_forms = [jit.form(f) for f in shell.energy_forms(inside)]
        self.sections = SectionForces(shell, tape.contact.nodes, tape.comm)
        self.vertex_columns = _vertex_columns(shell.mesh, tape.comm)

    def stretch(self, winding: tuple[float, float]) -> tuple[float, float]:
        """The material bounds (xi_1) [m] of the cells wholly inside the winding angles
        ``winding`` [rad] of the centre line (element edges: the mesh's columns of vertices)."""
        line = self.tape.centre_line()
        inside = line["xi1"][(line["psi"] >= winding[0]) & (line["psi"] <= winding[1])]
        if inside.size < 2:
            raise ValueError(f"no stretch of coil between winding angles {winding} rad")
        edges = self.vertex_columns
        edges = edges[(edges >= inside.min() - 1e-12) & (edges <= inside.max() + 1e-12)]
        if edges.size < 2:
            raise ValueError(f"the winding angles {winding} rad hold no whole element")
        return float(edges[0]), float(edges[-1])

    def energy_per_length(self, winding: tuple[float, float]) -> float:
        """Strain energy per unit (material) length of the stretch [J/m]."""
        a, b = self.stretch(winding)
        self.bounds[0].value, self.bounds[1].value = a, b
        comm = self.tape.comm
        return sum(global_scalar(form, comm) for form in self.energy_forms) / (b - a)

    def edge_rise(self, winding: tuple[float, float]) -> float:
        """How much further from the hub axis the two free edges lie than the centre line over
        the nodes of the stretch (mean of both edges) [m]."""
        tape = self.tape

        def mean_radius(line):
            inside = (line["psi"] >= winding[0]) & (line["psi"] <= winding[1])
            return float(line["radius"][inside].mean())

        edges = edge_lines(tape)
        return 0.5 * (mean_radius(edges[0]) + mean_radius(edges[1])) - mean_radius(tape.centre_line())

    def axial_force(self, winding: tuple[float, float]) -> np.ndarray:
        """Axial force N [N] (tension positive) across each section of the stretch."""
        cut = self.sections()
        line = self.tape.centre_line()
        psi = np.interp(cut["xi1"], line["xi1"], line["psi"])
        inside = (psi >= winding[0]) & (psi <= winding[1])
        if not inside.any():
            raise ValueError(f"no section between winding angles {winding} rad")
        return cut["axial_force"][inside]


def _vertex_columns(mesh, comm) -> np.ndarray:
    """The distinct xi_1 of the mesh's vertices on every rank, sorted: where its cells begin and
    end along the tape [m]."""
    mesh.topology.create_connectivity(0, mesh.topology.dim)
    n_vertices = mesh.topology.index_map(0).size_local
    geometry = dolfinx.mesh.entities_to_geometry(mesh, 0, np.arange(n_vertices, dtype=np.int32))
    xi1 = mesh.geometry.x[geometry.reshape(-1), 0]
    scale = max(comm.allreduce(float(np.abs(xi1).max()) if xi1.size else 0.0, op=MPI.MAX), 1.0)
    keys = np.unique(np.round(xi1 / (1e-9 * scale)).astype(np.int64))
    return np.unique(np.concatenate(comm.allgather(keys))) * (1e-9 * scale)
