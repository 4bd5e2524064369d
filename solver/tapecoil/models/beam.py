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
curvature K_n added to K_0 and a constant energy per unit length (a flattened tape's section,
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

Units: SI (metres, newtons); nothing here is specific to a tape but :meth:`BeamSection.circular_arc`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import basix.ufl
import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.core import compat
from tapecoil.core.dofs import owned_subspace_dofs
from tapecoil.core.newton import PointForce, SNESSolver
from tapecoil.core.rotation import rotation_matrix
from tapecoil.core.stepping import Continuation, StepRecord
from tapecoil.theory import arc_second_moment

__all__ = ["BeamProblem", "BeamSection", "GeometricallyExactBeam", "create_beam_mesh"]

# a cell's section as a DG0 vector: EA, GA2, GA3, GJ, EI2, EI3, natural curvature (3), energy offset
SECTION_FIELDS = 10
# below this a^2 = |theta|^2 [rad^2] Rodrigues' coefficients are their Taylor series (error < 1e-17)
SERIES_BELOW = 1e-4


@dataclass(frozen=True)
class BeamSection:
    """The stiffnesses of a beam's section, in its frame (axis 1 along the beam, 2 and 3 across).

    Attributes:
        EA: axial stiffness [N].
        GA2, GA3: shear stiffnesses along axes 2 and 3 [N].
        GJ: torsional stiffness [N m^2].
        EI2, EI3: bending stiffnesses about axes 2 and 3 [N m^2].
    """

    EA: float
    GA2: float
    GA3: float
    GJ: float
    EI2: float
    EI3: float
    natural_curvature: tuple[float, float, float] = (0.0, 0.0, 0.0)
    energy_offset: float = 0.0

    def __post_init__(self):
        for name in ("EA", "GA2", "GA3", "GJ", "EI2", "EI3"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"beam section: {name} must be a positive number, got {value!r}")
        if len(self.natural_curvature) != 3 or not all(math.isfinite(k) for k in self.natural_curvature):
            raise ValueError(
                f"beam section: natural_curvature must be 3 numbers, got {self.natural_curvature!r}"
            )
        if not math.isfinite(self.energy_offset):
            raise ValueError(f"beam section: energy_offset must be a number, got {self.energy_offset!r}")

    @classmethod
    def flattened_strip(
        cls,
        D11: float,
        D12: float,
        D22: float,
        R: float,
        width: float,
        h: float,
        E: float,
        nu: float,
        coil_sign: float = 1.0,
    ) -> BeamSection:
        """A tape's section flattened in an opposite-sense coil, as a beam: its energy per unit
        length b w(kappa) = (b/2)(D11 kappa^2 + D22/R^2 + 2 D12 kappa/R) (physics brief Sec. 3 and
        10), kappa = ``coil_sign`` K2 the coil's curvature, is (b D11/2)(K2 - K2_n)^2 plus the
        constant (b/2)(D22 - D12^2/D11)/R^2 [J/m]: a beam of bending stiffness b D11 about axis 2
        whose natural curvature K2_n = -coil_sign D12/(D11 R) (a flattened strip curls the other
        way by nu/R when let go). The flat strip's other stiffnesses: EA = E b h, EI3 = E h b^3/12,
        GJ = G b h^3/3, shear 5/6 E b h/(2(1 + nu)). Rigidities D [N m], R, width b, h [m], E [Pa].
        """
        G = E / (2 * (1 + nu))
        return cls(
            EA=E * width * h,
            GA2=G * width * h * 5 / 6,
            GA3=G * width * h * 5 / 6,
            GJ=G * width * h**3 / 3,
            EI2=width * D11,
            EI3=E * h * width**3 / 12,
            natural_curvature=(0.0, -coil_sign * D12 / (D11 * R), 0.0),
            energy_offset=width / 2 * (D22 - D12**2 / D11) / R**2,
        )

    @classmethod
    def rectangle(
        cls, E: float, nu: float, width: float, depth: float, torsion_constant: float | None = None
    ) -> BeamSection:
        """A solid rectangle ``width`` (along axis 2) by ``depth`` (along axis 3) [m] of an isotropic
        material E [Pa], nu; shear factor 5/6. ``torsion_constant`` J [m^4] defaults to Saint-Venant's
        series for the rectangle (0.1406 a^4 for a square of side a)."""
        G = E / (2 * (1 + nu))
        A = width * depth
        if torsion_constant is None:
            a, b = max(width, depth), min(width, depth)
            torsion_constant = a * b**3 * (1 / 3 - 0.21 * (b / a) * (1 - (b / a) ** 4 / 12))
        return cls(
            EA=E * A,
            GA2=G * A * 5 / 6,
            GA3=G * A * 5 / 6,
            GJ=G * torsion_constant,
            EI2=E * width * depth**3 / 12,
            EI3=E * depth * width**3 / 12,
        )

    @classmethod
    def circular_arc(cls, R: float, alpha: float, h: float, E: float, nu: float) -> BeamSection:
        """The thin circular-arc section of a tape spring: radius R [m], angle alpha [rad], wall
        thickness h [m], isotropic wall E [Pa], nu. Axis 2 runs across the width (the chord), axis 3
        towards the centre of curvature; the beam's line is the section's centroid.

        Thin-walled formulas (wall of thickness h along the arc, phi in [-alpha/2, alpha/2]):
        A = R alpha h; I2 about the centroid, :func:`tapecoil.theory.arc_second_moment` (the
        shell's end rotation under a small end moment matches M L/(E I2) within 3 %: `tapecoil
        verify tape-linear`); I3 = (R^3 h + R h^3/12)(alpha - sin alpha)/2 (the wall's own
        bending weighted by its inclination); Saint-Venant torsion of an open section,
        J = R alpha h^3 / 3; shear areas 5/6 A (the tape is slender: shear barely acts). Warping
        and the shear centre's offset from the centroid are not modelled.
        """
        for name, value in (("R", R), ("alpha", alpha), ("h", h), ("E", E)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"arc section: {name} must be a positive number, got {value!r}")
        if not 0 < alpha <= 2 * math.pi:
            raise ValueError(f"arc section: alpha must lie in (0, 2 pi], got {alpha!r}")
        G = E / (2 * (1 + nu))
        A = R * alpha * h
        I3 = R**3 * h * (alpha - math.sin(alpha)) / 2 + h**3 / 12 * R * (alpha - math.sin(alpha)) / 2
        return cls(
            EA=E * A,
            GA2=G * A * 5 / 6,
            GA3=G * A * 5 / 6,
            GJ=G * R * alpha * h**3 / 3,
            EI2=E * arc_second_moment(R, alpha, h),
            EI3=E * I3,
        )

    @staticmethod
    def arc_centroid_depth(R: float, alpha: float) -> float:
        """Depth of an arc section's centroid below its middle, towards the centre of curvature [m]:
        R (1 - sin(alpha/2) / (alpha/2))."""
        return R * (1 - math.sin(alpha / 2) / (alpha / 2))


def create_beam_mesh(comm, centre_line: Callable[[np.ndarray], np.ndarray], length: float, elements: int):
    """A mesh of ``elements`` quadratic intervals along the curve ``centre_line(s)`` -> (n, 3)
    points [m], s the arc length from 0 to ``length`` [m] (the curve parametrised by arc length).
    Built on rank 0 and distributed over ``comm``."""
    if elements < 1:
        raise ValueError(f"a beam mesh needs at least one element, got {elements}")
    if not (math.isfinite(length) and length > 0):
        raise ValueError(f"a beam's length must be positive, got {length!r}")
    element = basix.ufl.element("Lagrange", "interval", 2, shape=(3,))
    if comm.rank == 0:
        s = np.linspace(0.0, length, 2 * elements + 1)
        x = np.asarray(centre_line(s), dtype=float).reshape(-1, 3)
        cells = np.column_stack(
            [2 * np.arange(elements), 2 * np.arange(elements) + 2, 2 * np.arange(elements) + 1]
        )
    else:
        x, cells = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return compat.create_mesh(comm, cells.astype(np.int64), x, ufl.Mesh(element))


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
        self.mesh, self.section = mesh, section
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
        self.curvature_n = at_quadrature((3,), "curvature_n")  # K_n
        self.curvature_0 = at_quadrature((3,), "curvature_0")  # K_0, stress-free
        self.strain_0 = at_quadrature((3,), "strain_0")  # Gamma_0 = Lambda_0^T X', stress-free

        # the reference: the frame and its curvature at the quadrature points (numpy), then
        # Gamma_0 from the mesh's own tangent so that the reference is stress-free exactly
        extent = np.ptp(mesh.geometry.x, axis=0).max() if len(mesh.geometry.x) else 0.0
        size = mesh.comm.allreduce(extent, op=MPI.MAX)
        points = compat.interpolation_points(self.frame_n.function_space)
        x = self._at_points(dolfinx.fem.Expression(ufl.SpatialCoordinate(mesh), points)).reshape(-1, 3).T
        F0, K0 = _frames_with_curvature(frame, x, 1e-6 * size)
        _store(self.frame_n, F0)
        _store(self.curvature_0, K0)
        _store(self.curvature_n, K0)
        J = ufl.Jacobian(mesh)
        tangent = ufl.as_vector([J[i, 0] for i in range(3)])
        self.tangent = tangent / ufl.sqrt(ufl.dot(tangent, tangent))
        self.strain_0.interpolate(dolfinx.fem.Expression(self.frame_n.T * self.tangent, points))

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
        natural = ufl.as_vector([c[6], c[7], c[8]])
        bend = self.curvature - self.curvature_0 - natural
        self.energy_density = (
            0.5 * ufl.dot(self.strain, C_N * self.strain) + 0.5 * ufl.dot(bend, C_M * bend) + c[9]
        )
        self.energy = self.energy_density * self.dx
        self.residual = ufl.derivative(self.energy, self.q, self.dq)
        self.jacobian = ufl.derivative(self.residual, self.q, ufl.TrialFunction(self.W))
        self._next_frame = dolfinx.fem.Expression(self.frame, points)
        self._next_curvature = dolfinx.fem.Expression(self.curvature, points)
        _, theta_map = compat.collapse(self.W.sub(1))
        self._theta_dofs = theta_map

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
        return values.reshape(len(cells), n_points, -1)

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
        """Accept the current state: Lambda_n <- R(theta) Lambda_n, K_n <- K, theta <- 0.

        Both new fields are evaluated before either is stored (each reads the old frame).
        """
        curvature = self._at_points(self._next_curvature)
        frame = self._at_points(self._next_frame)
        _store(self.curvature_n, curvature)
        _store(self.frame_n, frame)
        self.q.x.array[self._theta_dofs] = 0.0
        self.q.x.scatter_forward()

    def strain_energy(self) -> float:
        """The beam's strain energy [J] (collective)."""
        local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(self.energy))
        return self.mesh.comm.allreduce(local, op=MPI.SUM)


class _Scaled:
    """A point load's magnitude: ``factor`` times the load parameter (read when the residual is)."""

    def __init__(self, load, factor: float):
        self.load, self.factor = load, factor

    @property
    def value(self) -> float:
        return self.factor * self.load[0]


class BeamProblem:
    """A beam stated as a benchmark is: line, section, frame, supports, loads, load steps.

    ``centre_line(s)`` and ``length``, ``elements``: the mesh (:func:`create_beam_mesh`);
    ``section``, ``frame``: see :class:`GeometricallyExactBeam`. Loads are given per unit of a load
    parameter (or held constant), and :meth:`solve` steps the parameter; a clamp may turn with it
    as an angle. ``name``: the PETSc options prefix is ``name + "_"``.
    """

    def __init__(self, centre_line, length, elements, section, frame, *, comm=MPI.COMM_WORLD, name="beam"):
        self.mesh = create_beam_mesh(comm, centre_line, length, elements)
        self.mesh.topology.create_connectivity(0, 1)
        self.model = GeometricallyExactBeam(self.mesh, section, frame)
        self.name = name
        self.load = [0.0]
        self.committed_load = 0.0  # the load parameter of the last accepted step
        self.bcs: list = []
        self.point_forces: list[PointForce] = []
        self.energy_terms: list = []  # UFL energies beside the beam's own (contact)
        self._turning: list[tuple] = []  # (u function, theta function, point, axis point, axis)
        self.history: list[StepRecord] = []

    def _vertices(self, point) -> np.ndarray:
        p = np.asarray(point, dtype=float)
        scale = 1e-9 * (1.0 + np.abs(self.mesh.geometry.x).max(initial=0.0))
        found = dolfinx.mesh.locate_entities(
            self.mesh, 0, lambda x: np.all(np.abs(x - p[:, None]) <= scale, axis=0)
        )
        if self.mesh.comm.allreduce(len(found), op=MPI.MAX) == 0:
            raise ValueError(f"no node of the beam at {tuple(p)}")
        return found

    def _dirichlet(self, sub: tuple[int, ...], vertices):
        """A Dirichlet condition on the subspace ``sub`` at ``vertices`` and the Function of its values."""
        space = self.model.W
        for i in sub:
            space = space.sub(i)
        collapsed, _ = space.collapse()
        dofs = dolfinx.fem.locate_dofs_topological((space, collapsed), 0, vertices)
        values = dolfinx.fem.Function(collapsed)
        self.bcs.append(dolfinx.fem.dirichletbc(values, dofs, space))
        return values

    def clamp(self, point, turning_about: tuple | None = None) -> None:
        """Hold the node at ``point`` [m]: its displacement and rotation. ``turning_about`` =
        (a point of the axis [m], the axis's direction): the clamp turns about that axis by the
        load parameter [rad] (a hub that the beam's root is fixed to)."""
        vertices = self._vertices(point)
        u_values = self._dirichlet((0,), vertices)
        theta_values = self._dirichlet((1,), vertices)
        if turning_about is not None:
            centre, axis = (np.asarray(v, dtype=float) for v in turning_about)
            axis = axis / np.linalg.norm(axis)
            self._turning.append((u_values, theta_values, np.asarray(point, dtype=float), centre, axis))

    def hold(self, point, components: tuple[int, ...], rotation: bool = False) -> None:
        """Hold the displacement components ``components`` (0, 1, 2: x, y, z) of the node at
        ``point`` at zero (a guide the node slides along) and, with ``rotation``, its rotation."""
        vertices = self._vertices(point)
        for i in components:
            self._dirichlet((0, i), vertices)
        if rotation:
            self._dirichlet((1,), vertices)

    def end_load(self, point, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0), *, constant=False) -> None:
        """A force [N] and a moment [N m] on the node at ``point``, per unit load parameter (or,
        ``constant``, as given at every load), both of fixed direction (dead loads); the moment
        does work on the spatial rotation, exactly so when it keeps its axis (plane bending)."""
        vertices = self._vertices(point)
        scale = [1.0] if constant else self.load
        for sub, vector in ((0, force), (1, moment)):
            for i, value in enumerate(vector):
                if value != 0.0:
                    dofs = owned_subspace_dofs(self.model.W, (sub, i), 0, vertices)
                    self.point_forces.append(PointForce(dofs, _Scaled(scale, float(value))))

    def hub_contact(self, axis_point, axis, radius: float, penalty: float) -> None:
        """Keep the beam's line at least ``radius`` [m] from the axis through ``axis_point`` along
        ``axis``: the energy (k/2) <radius - distance>^2 per unit length, k = ``penalty``
        [N/m^2] (a rigid hub; the line penetrates it by about the pressure / k)."""
        if not (math.isfinite(penalty) and penalty > 0):
            raise ValueError(f"hub contact: the penalty must be a positive number, got {penalty!r}")
        centre = ufl.as_vector([float(c) for c in axis_point])
        a = np.asarray(axis, dtype=float)
        a = ufl.as_vector((a / np.linalg.norm(a)).tolist())
        d = ufl.SpatialCoordinate(self.mesh) + self.model.u - centre
        radial = d - ufl.dot(d, a) * a
        distance = ufl.sqrt(ufl.dot(radial, radial))
        penetration = ufl.max_value(radius - distance, 0.0)
        self.energy_terms.append(0.5 * penalty * penetration**2 * self.model.dx)

    def _set_load(self, value: float) -> None:
        self.load[0] = value
        for u_values, theta_values, point, centre, axis in self._turning:
            R = rotation_matrix(axis, value)
            u = R @ (point - centre) + centre - point
            u_values.x.array[:] = np.tile(u, len(u_values.x.array) // 3)
            increment = (value - self.committed_load) * axis  # the rotation since the last accepted step
            theta_values.x.array[:] = np.tile(increment, len(theta_values.x.array) // 3)

    def _commit(self) -> None:
        self.model.commit()
        self.committed_load = self.load[0]
        for _, theta_values, *_ in self._turning:
            theta_values.x.array[:] = 0.0

    def solve(
        self,
        load_end: float,
        *,
        first_step: float,
        max_step: float,
        min_step: float = 1e-4,
        grow: float = 1.5,
        cutback: float = 0.5,
        max_cutbacks: int = 8,
        rtol: float = 1e-9,
        atol: float = 1e-12,
        on_step=None,
        options: dict | None = None,
    ) -> list[StepRecord]:
        """Step the load parameter from where it is to ``load_end``; steps are fractions of the
        span; ``options``: PETSc options for the solver (names without the prefix). Raises
        :class:`~tapecoil.core.stepping.ContinuationError` (the last converged state kept) when no
        step converges."""
        from tapecoil.config import StepControl

        model = self.model
        energy = model.energy + sum(self.energy_terms)
        residual = ufl.derivative(energy, model.q, model.dq)
        jacobian = ufl.derivative(residual, model.q, ufl.TrialFunction(model.W))
        solver = SNESSolver(
            residual,
            jacobian,
            model.q,
            self.bcs,
            prefix=f"{self.name}_",
            options={"pc_factor_mat_solver_type": "mumps", "pc_type": "cholesky", **(options or {})},
            rtol=rtol,
            atol=atol,
            state_scale=model.rounding_scale(),
        )
        solver.point_forces = self.point_forces
        control = StepControl(first_step, max_step, min_step, grow, cutback, max_cutbacks)
        continuation = Continuation(
            solve=solver.solve,
            set_load=self._set_load,
            state=model.q,
            control=control,
            commit=self._commit,
            on_step=on_step,
        )
        try:
            self.history += continuation.run(self.committed_load, load_end)
        finally:
            solver.destroy()
        return self.history

    def axial_force(self) -> tuple[np.ndarray, np.ndarray]:
        """The axial force N = EA Gamma_1 [N] at every quadrature point of the beam, with the
        points' reference positions (n, 3) [m], gathered on every rank (collective)."""
        model = self.model
        points = compat.interpolation_points(model.frame_n.function_space)
        index_map = self.mesh.topology.index_map(1)
        cells = np.arange(index_map.size_local, dtype=np.int32)
        force = dolfinx.fem.Expression(model.section_fields[0] * model.strain[0], points).eval(
            self.mesh, cells
        )
        where = dolfinx.fem.Expression(ufl.SpatialCoordinate(self.mesh), points).eval(self.mesh, cells)
        comm = self.mesh.comm
        x = np.concatenate(comm.allgather(where.reshape(-1, 3)))
        N = np.concatenate(comm.allgather(force.reshape(-1)))
        return x, N

    def position(self, point) -> np.ndarray:
        """The current position [m] of the node whose reference position is ``point`` (collective)."""
        vertices = self._vertices(point)
        values = np.zeros(3)
        count = 0
        for i in range(3):
            dofs = owned_subspace_dofs(self.model.W, (0, i), 0, vertices)
            values[i] = self.model.q.x.array[dofs].sum()
            count = max(count, len(dofs))
        comm = self.mesh.comm
        values = comm.allreduce(values, op=MPI.SUM)
        if comm.allreduce(count, op=MPI.SUM) != 1:
            raise ValueError(f"expected one node at {tuple(point)}")
        return np.asarray(point, dtype=float) + values
