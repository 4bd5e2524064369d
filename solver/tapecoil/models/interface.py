"""A shell's edge tied to a beam's end node as a rigid section (Abaqus's MPC BEAM).

Every point X of the shell's edge keeps its place in the section frame of the beam's end: the
edge's position is phi(X) = r_e + Q (X - X_e) and its director is d(X) = Q n0(X), where r_e is
the end node's position, X_e its reference position and Q the rotation of its section since
the reference. Force and moment pass through the tie in full, and the section cannot deform
at the edge; how far from the edge that matters is measured in docs/notes/hybrid.md.

The section keeps the shape of the beam it is tied to: the arc (``section="arc"``, X - X_e and
n0 as above: a beam of the arc section, about the arc's centroid) or the flattened strip
(``section="flat"``: X - X_e replaced by (x - x_e, xi_2, 0), the strip laid flat across its
width about the beam's line, and n0 by the arc's normal at its middle: a beam of the flattened
strip's section, whose line is the flat strip's middle line). The shapes are those of a tape
along x whose section is an arc in the y-z plane (a strip's reference). :meth:`RigidSectionTie.keep_shape`
makes the tie hold the edge's present shape instead, in the end's present frame (offsets o + o'
and normals n + n', o' and n' nodal fields on the edge): a window moved along the tape ties a
section where the shell had it, and a turned arc is not exactly in the shell's discrete space,
so tying it to the exact arc would store the shell's interpolation error as penalty energy.

The tie is collocated at the edge's nodes (a Gauss-Lobatto rule through them). A rigid motion
of the exact arc is not in the discrete space (the reference map is exact, the displacement
polynomial), but at the nodes the interpolated motion is exact, so the tie there costs a rigid
motion nothing. At Gauss points it held the interpolation error of the arc (about 1e-6 m with
four elements across) against the penalty: 0.014 J against the shell's 1e-5 J in a rigid turn
of 0.1 rad, and the solves failed beyond half a radian.

The tie is a penalty energy on the edge (per unit physical length)

    E = 1/2 (k_u |phi - r_e - Q (X - X_e)|^2 + k_d |d - Q n0|^2),

k_u = p E h / l_e and k_d = p E h^3 / l_e, l_e the shell's element length along the tape and p
the penalty factor: p times the stiffness of one element of membrane, and of bending, per unit
length of the edge. It is the energy of a :class:`~tapecoil.core.coupled_newton.DofCoupling`
whose parameters are the beam end's six dofs (its displacement and its rotation increment, see
:mod:`tapecoil.models.beam`). Q = R(theta_e) Q_n: the beam's rotations are incremental, so the
tie keeps Q_n, the end's rotation at the last accepted step, and moves it on at each
:meth:`RigidSectionTie.commit`, as the beam moves on its frames.
"""

from __future__ import annotations

import math

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.core import compat
from tapecoil.core.coupled_newton import DofCoupling
from tapecoil.core.dofs import global_scalar, owned_subspace_dofs
from tapecoil.core.rotation import rotation_matrices
from tapecoil.models.beam import rotation, vertices_at

__all__ = ["SECTION_SHAPES", "RigidSectionTie", "section_shape"]

SECTION_SHAPES = ("arc", "flat")


def section_shape(R: float, xi: np.ndarray, end: np.ndarray, flatness: float):
    """A tape's section of flatness ``flatness`` (0: the arc of radius ``R`` [m], 1: flat; the
    arc of curvature (1 - f)/R between) at parameter points ``xi`` (2, n) [m], about the beam
    node ``end`` [m] ((3,), or (3, n) one for each point): its offsets (3, n) [m] and unit
    normals (3, n) in the beam's reference frame (see the module; numpy)."""
    k = 0.0 if math.isinf(R) else (1 - flatness) / R
    s = xi[1]
    end = np.asarray(end, dtype=float).reshape(3, -1)
    if abs(k) < 1e-12:
        across, depth = s, 0 * s
    else:
        across, depth = np.sin(k * s) / k, (1 - np.cos(k * s)) / k
    offsets = np.vstack([xi[0] - end[0], across, depth - (1 - flatness) * end[2]])
    return offsets, np.vstack([0 * s, -np.sin(k * s), np.cos(k * s)])


class RigidSectionTie:
    """The shell ``shell`` (:class:`~tapecoil.models.shell.NaghdiShell`) along its edge tagged
    ``edge`` tied to the beam ``beam`` (:class:`~tapecoil.models.beam.GeometricallyExactBeam`) at
    its node ``end`` [m] (the reference position X_e), with penalty factor ``penalty`` (see the
    module); ``element_length``: the shell's element length along the tape at the edge [m];
    ``modulus``: the wall's in-plane Young's modulus [Pa]; ``section``: the shape the edge keeps,
    ``"arc"`` or ``"flat"`` (see the module). Collective.
    """

    def __init__(
        self,
        shell,
        edge: int,
        beam,
        end,
        *,
        element_length: float,
        modulus: float,
        penalty=1e3,
        section: str = "arc",
    ):
        if section not in SECTION_SHAPES:
            raise ValueError(f"rigid section tie: section must be one of {SECTION_SHAPES}, got {section!r}")
        for name, value in (("penalty", penalty), ("element_length", element_length), ("modulus", modulus)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"rigid section tie: {name} must be a positive number, got {value!r}")
        self.shell, self.beam, self.section = shell, beam, section
        self.edge = edge
        self.end = np.asarray(end, dtype=float)
        vertices = vertices_at(beam.mesh, self.end)
        dofs = []
        for sub in (0, 1):
            for i in range(3):
                found = owned_subspace_dofs(beam.W, (sub, i), 0, vertices)
                dofs.append(int(found[0]) if len(found) else -1)
        self.coupling = DofCoupling(shell.mesh, beam.q, dofs)
        self.turned = dolfinx.fem.Constant(shell.mesh, np.eye(3))  # Q_n

        h = shell.material.h
        self.k_u = penalty * modulus * h / element_length  # [N/m^2]
        self.k_d = penalty * modulus * h**3 / element_length  # [N]
        # every number a Constant, not a literal: every tie at an edge, of either shape, then
        # compiles to the same forms (compiling them takes about a minute)
        stiffness = dolfinx.fem.Constant(shell.mesh, np.array([self.k_u, self.k_d]))
        X_e = dolfinx.fem.Constant(shell.mesh, self.end)
        # the section's flatness f: the arc (0) flattened to the flat strip (1) through the arcs
        # of curvature (1 - f)/R, each of the strip's width; a flat tie may be flattened by steps
        self.flatness = dolfinx.fem.Constant(shell.mesh, 1.0 if section == "flat" else 0.0)
        self.R = shell.strip.geometry.R
        c = self.coupling.variable
        displacement = ufl.as_vector([c[0], c[1], c[2]])
        Q = rotation(ufl.as_vector([c[3], c[4], c[5]])) * self.turned
        xi = ufl.SpatialCoordinate(shell.mesh)
        inverse_radius = dolfinx.fem.Constant(shell.mesh, 0.0 if math.isinf(self.R) else 1.0 / self.R)
        k = (1 - self.flatness) * inverse_radius
        straight = ufl.lt(abs(k), 1e-12)
        k_safe = ufl.conditional(straight, 1.0, k)
        across = ufl.conditional(straight, xi[1], ufl.sin(k * xi[1]) / k_safe)
        depth = ufl.conditional(straight, 0.0, (1 - ufl.cos(k * xi[1])) / k_safe)
        # about the beam's line: the arc's centroid (X_e) for the arc, the strip's middle when flat
        self._offset = ufl.as_vector([xi[0] - X_e[0], across, depth - (1 - self.flatness) * X_e[2]])
        self._normal = ufl.as_vector([0.0, -ufl.sin(k * xi[1]), ufl.cos(k * xi[1])])
        # the shape kept (keep_shape): nodal fields, zero but on the edge
        space, self._space_dofs = compat.collapse(shell.W.sub(0))
        self.kept_offset = dolfinx.fem.Function(space, name="tie_kept_offset")
        self.kept_normal = dolfinx.fem.Function(space, name="tie_kept_normal")
        offset = self._offset + self.kept_offset
        normal = self._normal + self.kept_normal
        self.position_gap = shell.phi - (X_e + displacement) - Q * offset
        self.director_gap = shell.d - Q * normal
        tangent = shell.J0[:, 1]  # along the edge, which lies across the tape (xi_1 fixed)
        self.line_element = ufl.sqrt(ufl.dot(tangent, tangent))
        density = (
            0.5
            * (
                stiffness[0] * ufl.dot(self.position_gap, self.position_gap)
                + stiffness[1] * ufl.dot(self.director_gap, self.director_gap)
            )
            * self.line_element
        )
        mesh = shell.mesh
        tdim = mesh.topology.dim
        facets = shell.strip.facet_tags.find(edge)
        # collocated at the edge's nodes (Gauss-Lobatto points), where the discrete section
        # can follow a rigid motion exactly (see the module); the strip's own facet tags, which
        # every boundary integral of a form must share
        self.measure = ufl.Measure(
            "ds",
            domain=mesh,
            subdomain_data=shell.strip.facet_tags,
            metadata={"quadrature_rule": "GLL", "quadrature_degree": 2 * shell.degree - 1},
        )(edge)
        mesh.topology.create_connectivity(tdim - 1, tdim)
        f2c = mesh.topology.connectivity(tdim - 1, tdim)
        cells = np.unique(np.concatenate([f2c.links(f) for f in facets])) if len(facets) else []
        self.coupling.set_energy(density, self.measure, shell.q, cells)

    def commit(self) -> None:
        """Accept the current state: Q_n <- R(theta_e) Q_n (call before the beam's own commit,
        which sets theta back to zero). Collective."""
        self.coupling.read()
        R = rotation_matrices(np.array(self.coupling.c.value[3:6]))[0]
        self.turned.value[:] = R @ np.asarray(self.turned.value)

    def state_fields(self) -> dict:
        """The kept shape of the edge, as cell fields (a restart's)."""
        from tapecoil.core.cell_state import function_field

        return {
            "kept_offset": function_field(self.kept_offset),
            "kept_normal": function_field(self.kept_normal),
        }

    def state_values(self) -> dict:
        """The end's accepted rotation Q_n and the section's flatness."""
        return {"turned": np.array(self.turned.value, dtype=float), "flatness": float(self.flatness.value)}

    def set_state_values(self, values: dict) -> None:
        self.turned.value[:] = np.asarray(values["turned"], dtype=float)
        self.flatness.value = float(values["flatness"])

    def keep_shape(self) -> None:
        """Tie the edge in the shape it has now in the beam end's present frame: the kept offsets
        and normals become those that make both gaps zero at the edge's nodes (collective; call
        at an accepted step, the end's rotation increment zero)."""
        from tapecoil.models.nodes import Nodes

        self.coupling.read()
        if np.abs(self.coupling.c.value[3:6]).max() > 0.0:
            raise ValueError("keep_shape: the beam end's rotation increment is not zero")
        nodes = Nodes(self.shell)
        q = self.shell.q.x.array
        x_edge = self.end[0]
        on_edge = np.isclose(nodes.xi[0], x_edge, rtol=0, atol=1e-9 * (1.0 + abs(x_edge)))
        xi = nodes.xi[:, on_edge]
        positions = nodes.positions(q)[:, on_edge]
        directors = nodes.directors(q)[:, on_edge]
        Q = np.asarray(self.turned.value)
        end = self.end + np.asarray(self.coupling.c.value[:3])
        # the present offsets and normals in the end's frame, less the shape's own
        offset = Q.T @ (positions - end[:, None])
        normal = Q.T @ directors
        shape_offset, shape_normal = self._shape_numpy(xi)
        inverse = np.full(len(q), -1, dtype=np.int64)
        inverse[self._space_dofs] = np.arange(len(self._space_dofs))
        for field, values in (
            (self.kept_offset, offset - shape_offset),
            (self.kept_normal, normal - shape_normal),
        ):
            field.x.array[:] = 0.0
            field.x.array[inverse[nodes.u_dofs[on_edge]]] = values.T
            field.x.scatter_forward()

    def copy_shape(self, other: RigidSectionTie) -> None:
        """Take the kept shape of ``other``, a tie at the same node of a shell with the same
        nodes (a window moved at its other end)."""
        from scipy.spatial import cKDTree

        comm = self.shell.mesh.comm
        old_points, offsets, normals = (
            np.concatenate(comm.allgather(a))
            for a in (
                other.kept_offset.function_space.tabulate_dof_coordinates()[:, :2],
                other.kept_offset.x.array.reshape(-1, 3),
                other.kept_normal.x.array.reshape(-1, 3),
            )
        )
        new_points = self.kept_offset.function_space.tabulate_dof_coordinates()[:, :2]
        tree = cKDTree(old_points)
        distance, index = tree.query(new_points) if len(new_points) else (np.zeros(0), np.zeros(0, int))
        scale = 1e-9 * (1.0 + abs(self.end[0]))
        on_edge = np.isclose(new_points[:, 0], self.end[0], rtol=0, atol=scale)
        if comm.allreduce(float(distance[on_edge].max(initial=0.0)), op=MPI.MAX) > scale:
            raise ValueError("copy_shape: the two ties' edges do not share their nodes")
        for field, values in ((self.kept_offset, offsets), (self.kept_normal, normals)):
            array = field.x.array.reshape(-1, 3)
            array[:] = 0.0
            array[on_edge] = values[index[on_edge]]
            field.x.scatter_forward()

    def _shape_numpy(self, xi: np.ndarray):
        """The shape's offsets and normals (3, n) at edge points ``xi`` (2, n), as the forms have them."""
        return section_shape(self.R, xi, self.end, float(self.flatness.value))

    def gaps(self) -> tuple[float, float]:
        """The root-mean-square position gap [m] and director gap over the edge: a consistency
        check of the tie, which holds them to about force / k (collective)."""
        self.coupling.read()
        comm = self.shell.mesh.comm
        length = global_scalar(self.line_element * self.measure, comm)
        rms = [
            math.sqrt(
                max(global_scalar(ufl.dot(g, g) * self.line_element * self.measure, comm), 0.0) / length
            )
            for g in (self.position_gap, self.director_gap)
        ]
        return rms[0], rms[1]
