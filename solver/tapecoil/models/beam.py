"""A geometrically exact beam (Simo-Reissner rod): large displacements and rotations, any number of turns.

Kinematics (Simo 1985; Simo and Vu-Quoc 1986). The beam's line is r(s) = X(s) + u(s), s the
reference arc length, and its section frame Lambda(s) = [t, e2, e3], a rotation matrix whose first
column is the section's normal. In the section's frame the strains are
Gamma = Lambda^T r' - Gamma_0 (extension and the two shears) and K = axial(Lambda^T Lambda')
(torsion and the two bending curvatures); the energy per unit length is
(1/2) Gamma . C_N Gamma + (1/2) (K - K_0) . C_M (K - K_0), C_N = diag(EA, GA2, GA3),
C_M = diag(GJ, EI2, EI3), with Gamma_0 and K_0 those of the stress-free reference (so the
reference is stress-free exactly, whatever the interpolation of its geometry). Each element
carries its section (:meth:`GeometricallyExactBeam.set_section`): the stiffnesses, a natural
curvature K_nat added to K_0, a constant energy per unit length and the free edges' relief of a
flattened coil, a function of the curvature (a flattened tape's section,
:meth:`BeamSection.flattened_strip`).

Rotations are updated, not totalled (Cardona and Geradin 1988; Ibrahimbegovic 1995). The unknown
theta is the spatial rotation vector of the current load step: Lambda = exp(theta^) Lambda_n,
where Lambda_n and the curvature K_n of the last accepted step are kept at the quadrature points,
and K = Lambda_n^T axial(R^T R') + K_n with R = exp(theta^). Once a step is accepted,
:meth:`GeometricallyExactBeam.commit` moves Lambda_n and K_n on and sets theta back to zero. A
rotation vector thus never holds more than one step's rotation, and the beam can wind any number
of turns (a total rotation vector's map to rotations is singular at |theta| = 2 pi). The price
is that the interpolated increments are not objective (Crisfield and Jelenic 1999): the
accumulated curvature depends slightly on the path, an error that vanishes with the mesh.
R(theta) is Rodrigues' formula I + f1 Theta + f2 Theta^2, f1 = sin a / a, f2 = (1 - cos a)/a^2,
a = |theta|, written as functions of a^2 with their Taylor series below a^2 = 1e-4, so that the
Jacobian at theta = 0 (every step's start) carries the exact second-order term.

Discretisation: u and theta continuous, Lagrange of degree 2 (the mesh's geometry too), the
energy integrated with two Gauss points per element (reduced: free of shear locking for slender
beams). The Jacobian is the energy's exact second derivative, symmetric: MUMPS LDL^T.

Units: SI (metres, newtons); nothing here is specific to a tape (its sections are in
:mod:`tapecoil.models.beam_section`; a beam problem stated as a benchmark is in
:mod:`tapecoil.models.beam_problem`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import basix.ufl
import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.core import compat, jit
from tapecoil.core.dofs import global_scalar
from tapecoil.core.expression import expression_at
from tapecoil.core.rotation import rotation_matrices
from tapecoil.models.beam_section import BeamSection

__all__ = ["BeamSection", "GeometricallyExactBeam", "create_beam_mesh", "vertices_at"]

# a cell's section as a DG0 vector: EA, GA2, GA3, GJ, EI2, EI3, natural curvature (3), energy offset,
# edge relief (5)
SECTION_FIELDS = 15
# below this a^2 = |theta|^2 [rad^2] Rodrigues' coefficients are their Taylor series (error < 1e-17)
SERIES_BELOW = 1e-4


def create_beam_mesh(comm, centre_line: Callable[[np.ndarray], np.ndarray], length, elements):
    """A mesh of quadratic intervals along the curve ``centre_line(s)`` -> (n, 3) points [m], s
    the arc length (the curve parametrised by arc length): ``elements`` of them from s = 0 to
    ``length`` [m]; or, with ``length`` a sequence of spans (s_start, s_end) [m] and
    ``elements`` one count for each, those spans alone, each a piece of its own (the beam on
    both sides of a hybrid's shell window). Built on rank 0 and distributed over ``comm``."""
    spans = [(0.0, length)] if np.ndim(length) == 0 else [tuple(span) for span in length]
    counts = [elements] if np.ndim(elements) == 0 else list(elements)
    if len(counts) != len(spans):
        raise ValueError(f"a beam mesh needs one element count per span, got {counts} for {spans}")
    for (start, end), count in zip(spans, counts, strict=True):
        if count < 1:
            raise ValueError(f"a beam mesh needs at least one element per span, got {count}")
        if not (math.isfinite(start) and math.isfinite(end) and end > start):
            raise ValueError(f"a beam's span must have a positive length, got ({start!r}, {end!r})")
    element = basix.ufl.element("Lagrange", "interval", 2, shape=(3,))
    if comm.rank == 0:
        points, cells, first = [], [], 0
        for (start, end), count in zip(spans, counts, strict=True):
            points.append(np.asarray(centre_line(np.linspace(start, end, 2 * count + 1)), dtype=float))
            e = first + 2 * np.arange(count)
            cells.append(np.column_stack([e, e + 2, e + 1]))
            first += 2 * count + 1
        x, cells = np.concatenate([p.reshape(-1, 3) for p in points]), np.concatenate(cells)
    else:
        x, cells = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return compat.create_mesh(comm, cells.astype(np.int64), x, ufl.Mesh(element))


def vertices_at(mesh, point) -> np.ndarray:
    """The local vertices of a beam mesh at ``point`` [m] (to 1e-9 of its size); refused on every
    rank when no rank has one (collective)."""
    p = np.asarray(point, dtype=float)
    scale = 1e-9 * (1.0 + np.abs(mesh.geometry.x).max(initial=0.0))
    found = dolfinx.mesh.locate_entities(mesh, 0, lambda x: np.all(np.abs(x - p[:, None]) <= scale, axis=0))
    if mesh.comm.allreduce(len(found), op=MPI.MAX) == 0:
        raise ValueError(f"no node of the beam at {tuple(p)}")
    return found


def _skew(v):
    return ufl.as_matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def _axial(S):
    """The axial vector of the skew part of S."""
    return ufl.as_vector([(S[2, 1] - S[1, 2]) / 2, (S[0, 2] - S[2, 0]) / 2, (S[1, 0] - S[0, 1]) / 2])


def _rodrigues_coefficients(a2):
    """f1 = sin a / a and f2 = (1 - cos a)/a^2 as functions of a^2 (UFL), regular at 0."""
    small = ufl.lt(a2, SERIES_BELOW)
    safe = ufl.conditional(small, 1.0, a2)  # the unused branch never sees a^2 = 0
    a = ufl.sqrt(safe)
    f1 = ufl.conditional(small, 1 - a2 / 6 + a2**2 / 120 - a2**3 / 5040, ufl.sin(a) / a)
    f2 = ufl.conditional(small, 0.5 - a2 / 24 + a2**2 / 720 - a2**3 / 40320, 2 * ufl.sin(a / 2) ** 2 / safe)
    return f1, f2


def rotation(theta):
    """exp(theta^): the rotation by the rotation vector ``theta`` (UFL)."""
    f1, f2 = _rodrigues_coefficients(ufl.dot(theta, theta))
    T = _skew(theta)
    return ufl.Identity(3) + f1 * T + f2 * T * T


def _frames_with_curvature(frame, x: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The frames (n, 3, 3) at points x (3, n) and their curvature axial(F^T F') (n, 3), F' by a
    central difference of ``step`` [m] along each frame's first column."""
    F = np.asarray(frame(x), dtype=float)
    t = F[:, :, 0].T
    dF = (np.asarray(frame(x + step * t)) - np.asarray(frame(x - step * t))) / (2 * step)
    S = np.einsum("nji,njk->nik", F, dF)
    return F, np.column_stack([S[:, 2, 1] - S[:, 1, 2], S[:, 0, 2] - S[:, 2, 0], S[:, 1, 0] - S[:, 0, 1]]) / 2


def _store(function, values: np.ndarray) -> None:
    """Set a quadrature-space Function from values ordered (cell, point, component...), through
    its dofmap (every local cell, owned and ghost)."""
    dofmap = function.function_space.dofmap
    blocks = np.asarray(dofmap.list)
    bs = dofmap.index_map_bs
    flat = function.x.array.reshape(-1, bs)
    flat[blocks.reshape(-1)] = np.asarray(values).reshape(blocks.size, bs)


class GeometricallyExactBeam:
    """A Simo-Reissner beam on a mesh from :func:`create_beam_mesh` (see the module).

    ``section``: its :class:`BeamSection`; ``frame(x)``: the stress-free section frame at points
    x (3, n) [m] as (n, 3, 3) rotation matrices whose columns are the line's unit tangent and the
    section's axes 2 and 3; it must be defined near the line too (its curvature is taken by a
    central difference). The state ``q`` = (u [m], theta [rad]).
    """

    def __init__(self, mesh, section: BeamSection, frame: Callable[[np.ndarray], np.ndarray]):
        self.mesh = mesh
        cell = mesh.basix_cell()
        P2 = basix.ufl.element("Lagrange", cell, 2, shape=(3,))
        self.W = dolfinx.fem.functionspace(mesh, basix.ufl.mixed_element([P2, P2]))
        self.q = dolfinx.fem.Function(self.W, name="beam_state")
        self.dq = ufl.TestFunction(self.W)
        self.quadrature_degree = 3  # two Gauss points per element: reduced integration of P2
        self.dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": self.quadrature_degree})

        def at_quadrature(shape, name):
            element = basix.ufl.quadrature_element(cell, value_shape=shape, degree=self.quadrature_degree)
            return dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, element), name=name)

        self.frame_n = at_quadrature((3, 3), "frame_n")  # Lambda_n
        self.frame_0 = at_quadrature((3, 3), "frame_0")  # Lambda_0, the reference
        self.curvature_n = at_quadrature((3,), "curvature_n")  # K_n
        self.curvature_0 = at_quadrature((3,), "curvature_0")  # K_0, stress-free
        self.strain_0 = at_quadrature((3,), "strain_0")  # Gamma_0 = Lambda_0^T X', stress-free

        # the reference: the frame and its curvature at the quadrature points (numpy), then
        # Gamma_0 from the mesh's own tangent so that the reference is stress-free exactly
        extent = np.ptp(mesh.geometry.x, axis=0).max() if len(mesh.geometry.x) else 0.0
        size = mesh.comm.allreduce(extent, op=MPI.MAX)
        points = compat.interpolation_points(self.frame_n.function_space)
        x = self._at_points(expression_at(ufl.SpatialCoordinate(mesh), points)).reshape(-1, 3).T
        F0, K0 = _frames_with_curvature(frame, x, 1e-6 * size)
        _store(self.frame_n, F0)
        _store(self.frame_0, F0)
        _store(self.curvature_0, K0)
        _store(self.curvature_n, K0)
        J = ufl.Jacobian(mesh)
        tangent = ufl.as_vector([J[i, 0] for i in range(3)])
        self.tangent = tangent / ufl.sqrt(ufl.dot(tangent, tangent))
        self.strain_0.interpolate(expression_at(self.frame_n.T * self.tangent, points))

        self.u, self.theta = ufl.split(self.q)
        R = rotation(self.theta)
        self.frame = R * self.frame_n
        self.strain = self.frame.T * (self.tangent + self.d_ds(self.u)) - self.strain_0
        theta_v = ufl.variable(self.theta)
        dR = ufl.diff(rotation(theta_v), theta_v)  # (3, 3, 3): dR_ij / dtheta_k
        R_s = ufl.dot(dR, self.d_ds(self.theta))
        self.curvature = self.frame_n.T * _axial(R.T * R_s) + self.curvature_n
        # the section's stiffnesses cell by cell (one section everywhere unless set_section)
        dg0 = dolfinx.fem.functionspace(mesh, ("DG", 0, (SECTION_FIELDS,)))
        self.section_fields = dolfinx.fem.Function(dg0, name="section")
        self.set_section(np.arange(mesh.topology.index_map(1).size_local, dtype=np.int32), section)
        c = self.section_fields
        C_N = ufl.as_matrix([[c[0], 0, 0], [0, c[1], 0], [0, 0, c[2]]])
        C_M = ufl.as_matrix([[c[3], 0, 0], [0, c[4], 0], [0, 0, c[5]]])
        # the natural curvatures' share (1 but while a section is being flattened, see the hybrid)
        self.natural_share = dolfinx.fem.Constant(mesh, 1.0)
        natural = self.natural_share * ufl.as_vector([c[6], c[7], c[8]])
        # the bending strains (twist, then about the section's axes 2 and 3) that C_M holds
        self.bending_strain = bend = self.curvature - self.curvature_0 - natural
        # the flattened coil's free edges (BeamSection.edge_relief): kappa held above the floor
        # by a smooth maximum, so that the law stays bounded where it does not hold
        kappa = c[13] * (self.curvature[1] - self.curvature_0[1])
        kappa_held = 0.5 * (kappa + ufl.sqrt(kappa**2 + c[14] ** 2))
        relief = (c[10] + c[11] * kappa) ** 2 * c[12] / ufl.sqrt(kappa_held)
        self.energy_density = (
            0.5 * ufl.dot(self.strain, C_N * self.strain) + 0.5 * ufl.dot(bend, C_M * bend) + c[9] - relief
        )
        self.energy = self.energy_density * self.dx  # the solver differentiates it with its terms
        self._next_frame = expression_at(self.frame, points)
        self._next_curvature = expression_at(self.curvature, points)
        _, theta_map = compat.collapse(self.W.sub(1))
        self._theta_dofs = theta_map
        # the nodes (local and ghost): reference points, the dofs of u and theta at each, and the
        # section frames there, moved on at every commit as the quadrature points' are (a state
        # carried over to another model reads them)
        u_spaces = [compat.collapse(self.W.sub(0).sub(i)) for i in range(3)]
        self.node_points = u_spaces[0][0].tabulate_dof_coordinates()[:, :3].copy()
        self.node_u_dofs = np.column_stack([m for _, m in u_spaces])
        self.node_theta_dofs = np.column_stack([compat.collapse(self.W.sub(1).sub(i))[1] for i in range(3)])
        self.node_reference_frames = np.array(frame(self.node_points.T), dtype=float).reshape(-1, 3, 3)
        self.node_frames = self.node_reference_frames.copy()

    def set_section(self, cells: np.ndarray, section: BeamSection) -> None:
        """Give the owned ``cells`` (local indices) the stiffnesses, natural curvature and energy
        offset of ``section``; the ghosts follow (collective)."""
        values = np.array(
            [
                section.EA,
                section.GA2,
                section.GA3,
                section.GJ,
                section.EI2,
                section.EI3,
                *section.natural_curvature,
                section.energy_offset,
                *section.edge_relief,
            ]
        )
        dofs = np.asarray(self.section_fields.function_space.dofmap.list)[np.asarray(cells, dtype=np.int32)]
        array = self.section_fields.x.array.reshape(-1, SECTION_FIELDS)
        array[dofs.reshape(-1)] = values
        self.section_fields.x.scatter_forward()

    def _at_points(self, expression) -> np.ndarray:
        """An Expression at the quadrature points of every local cell (owned and ghost), as
        (cells, points, values...)."""
        index_map = self.mesh.topology.index_map(1)
        cells = np.arange(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
        values = expression.eval(self.mesh, cells)
        n_points = len(compat.interpolation_points(self.frame_n.function_space))
        size = int(np.prod(expression.ufl_expression.ufl_shape))  # a rank may hold no cell
        return values.reshape(len(cells), n_points, size)

    def quadrature_values(self, name: str) -> np.ndarray:
        """At the quadrature points of every local cell, in order: their reference positions
        (``"points"``, (n, 3) [m]), the committed frames (``"frame_n"``, (n, 9)), the reference
        frames (``"frame_0"``) or the committed curvatures (``"curvature_n"``, (n, 3) [1/m])."""
        fields = {"points": (ufl.SpatialCoordinate(self.mesh), 3), "frame_n": (self.frame_n, 9)}
        fields["frame_0"] = (self.frame_0, 9)
        fields["curvature_n"] = (self.curvature_n, 3)
        expression, size = fields[name]
        points = compat.interpolation_points(self.frame_n.function_space)
        return self._at_points(expression_at(expression, points)).reshape(-1, size)

    def set_quadrature_values(self, frames: np.ndarray, curvatures: np.ndarray) -> None:
        """Set the committed frames (n, 9) and curvatures (n, 3) at the quadrature points, in the
        order of :meth:`quadrature_values` (a state carried over from another beam)."""
        _store(self.frame_n, np.asarray(frames))
        _store(self.curvature_n, np.asarray(curvatures))

    def rounding_scale(self):
        """What each state component is added to, for the solver's round-off floor: a displacement
        to its node's reference position [m], a rotation increment to a frame of unit columns."""
        scale = dolfinx.fem.Function(self.W)
        space, dofs = compat.collapse(self.W.sub(0))
        position = dolfinx.fem.Function(space)
        position.interpolate(lambda x: np.abs(x))
        scale.x.array[dofs] = position.x.array
        scale.x.array[self._theta_dofs] = 1.0
        return scale

    def d_ds(self, f):
        """d f / ds along the reference line (UFL; f a vector field)."""
        return ufl.grad(f) * self.tangent

    def commit(self) -> None:
        """Accept the current state: Lambda_n <- R(theta) Lambda_n (at the quadrature points and
        the nodes), K_n <- K, theta <- 0.

        Both new fields are evaluated before either is stored (each reads the old frame).
        """
        curvature = self._at_points(self._next_curvature)
        frame = self._at_points(self._next_frame)
        _store(self.curvature_n, curvature)
        _store(self.frame_n, frame)
        self.node_frames = rotation_matrices(self.q.x.array[self.node_theta_dofs]) @ self.node_frames
        self.q.x.array[self._theta_dofs] = 0.0
        self.q.x.scatter_forward()

    def state_fields(self) -> dict:
        """The state an accepted step leaves, as :class:`~tapecoil.core.cell_state.CellField`
        views: ``q`` (its rotation increment zero), the committed frames and curvatures at the
        quadrature points and the nodes' frames (a restart's)."""
        from tapecoil.core.cell_state import CellField, function_field

        # the node arrays are indexed like the collapsed subspace's dofs they were built from
        space, _ = compat.collapse(self.W.sub(0).sub(0))
        self.node_frames = np.ascontiguousarray(self.node_frames)
        return {
            "q": function_field(self.q),
            "frame_n": function_field(self.frame_n),
            "curvature_n": function_field(self.curvature_n),
            "node_frames": CellField(
                self.mesh, np.asarray(space.dofmap.list), self.node_frames.reshape(-1, 9)
            ),
        }

    def strain_energy(self) -> float:
        """The beam's strain energy [J] (collective)."""
        if getattr(self, "_energy_form", None) is None:
            self._energy_form = jit.form(self.energy)  # compiled once, not at every call
        return global_scalar(self._energy_form, self.mesh.comm)
