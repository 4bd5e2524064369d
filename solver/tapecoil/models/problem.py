"""A shell problem stated as one states a benchmark: surface, material, supports, loads, steps.

The surface is a :class:`~tapecoil.geometry.surfaces.Surface` (one exact map, its Jacobian
derived from it and checked here). Edges are named by the parameter they bound, ``"xi1_min"``,
``"xi1_max"``, ``"xi2_min"``, ``"xi2_max"``, whatever the shell is. Supports are clamps,
symmetry planes and fixed points. Every load is given per unit of one load parameter lambda,
in the units the problem is stated in (N for a force, N m for a moment), and the load
stepping runs over lambda in those units::

    problem = ShellProblem(StripGeometry(R, math.pi * R, L), MeshResolution(20, 20), material)
    problem.clamp("xi1_min")
    problem.symmetry_plane("xi2_min", normal=(0, 0, 1))
    problem.point_force((L, 0.0), force=(0, 0, 1))
    problem.solve(2000.0, first_step=200.0, max_step=400.0)
    problem.displacement_at((L, 0.0))
"""

from __future__ import annotations

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.config import SolverConfig
from tapecoil.core.dofs import global_scalar, node_value, owned_node_dofs
from tapecoil.core.newton import PointForce, SNESSolver
from tapecoil.core.stepping import Continuation, StepRecord
from tapecoil.geometry.meshes import XI1_MAX, XI1_MIN, XI2_MAX, XI2_MIN, MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import Surface
from tapecoil.models.edges import clamp, facet_condition
from tapecoil.models.shell import NaghdiShell, ShellMaterial

EDGES = {"xi1_min": XI1_MIN, "xi1_max": XI1_MAX, "xi2_min": XI2_MIN, "xi2_max": XI2_MAX}
AXES = "xyz"


class _PerUnitLoad:
    """A point force component: ``factor`` times the load parameter, read when the residual is."""

    def __init__(self, load, factor: float):
        self.load, self.factor = load, factor

    @property
    def value(self) -> float:
        return self.factor * float(self.load.value)


class ShellProblem:
    """A Naghdi shell (:class:`NaghdiShell`, Q2, PSRI by default) on ``surface``, meshed at
    ``resolution``, with supports and loads added by the methods below before :meth:`solve`.

    ``name``: the PETSc options prefix of its solver is ``name + "_"`` (``-name_snes_monitor``).
    """

    def __init__(
        self,
        surface: Surface,
        resolution: MeshResolution,
        material: ShellMaterial,
        *,
        comm=MPI.COMM_WORLD,
        technology: str = "psri",
        name: str = "shell",
    ):
        surface.check()
        self.surface = surface
        self.strip = create_strip_mesh(comm, surface, resolution)
        self.model = NaghdiShell(self.strip, material, technology)
        self.name = name
        self.load = dolfinx.fem.Constant(self.strip.mesh, 0.0)  # lambda, the load parameter
        self.bcs: list = []
        self.work_per_load = None  # UFL form: the external work of the loads per unit lambda
        self.point_forces: list[PointForce] = []

    # --- where things are
    def edge(self, name: str) -> int:
        """The facet tag of the edge ``name``."""
        if name not in EDGES:
            raise ValueError(f"edge {name!r}: one of {', '.join(EDGES)} (the parameter bound it lies on)")
        return EDGES[name]

    def _facets(self, edge: str) -> np.ndarray:
        return self.strip.facet_tags.find(self.edge(edge))

    def _edge_points(self, edge: str) -> np.ndarray:
        """Parameter points (2, n) of this rank's dofs on the edge (some ranks hold none)."""
        V, _ = self.model.W.sub(0).sub(0).collapse()
        dofs = dolfinx.fem.locate_dofs_topological(V, 1, self._facets(edge))
        return V.tabulate_dof_coordinates()[dofs, :2].T

    def _line_element(self, edge: str):
        """Physical length per unit parameter length along the edge: |d phi0 / d xi_k|, k along it."""
        along = 1 if edge.startswith("xi1") else 0
        tangent = self.model.J0[:, along]
        return ufl.sqrt(ufl.dot(tangent, tangent))

    def _node_count(self, point) -> int:
        comm = self.strip.mesh.comm
        return comm.allreduce(len(owned_node_dofs(self.model.W, (0, 0), point)))

    def _require_node(self, point, what: str) -> None:
        if self._node_count(point) != 1:
            raise ValueError(f"{what}: no mesh node at the parameter point {tuple(point)}")

    # --- supports
    def clamp(self, edge: str) -> None:
        """The edge held: zero displacement and rotation."""
        self.bcs += clamp(self.model, self.edge(edge)).bcs

    def symmetry_plane(self, edge: str, normal) -> None:
        """The edge lies on a plane of symmetry with unit ``normal`` (a coordinate axis).

        The displacement along the normal vanishes and the director stays in the plane. The
        plane must contain the edge and the shell's normal there, so that it is normal to one
        of the edge's tangents t1 or t2; then keeping the director in the plane is, exactly,
        the vanishing of the one director angle that tilts it towards that tangent (theta_0
        towards t2, theta_1 towards t1).
        """
        n = np.asarray(normal, dtype=float)
        axis = int(np.argmax(np.abs(n)))
        if n.shape != (3,) or not np.isclose(abs(n[axis]), 1.0) or np.count_nonzero(n) != 1:
            raise ValueError(f"symmetry plane on {edge}: normal {tuple(n)} must be +-x, +-y or +-z")
        comm = self.strip.mesh.comm
        xi = self._edge_points(edge)
        X = self.surface.phi0(xi)[axis] if xi.size else np.empty(0)
        t1, t2, _ = self.surface.frame(xi) if xi.size else (np.zeros((3, 0)),) * 3
        lo = comm.allreduce(X.min(initial=np.inf), op=MPI.MIN)
        hi = comm.allreduce(X.max(initial=-np.inf), op=MPI.MAX)
        scale = max(1.0, np.abs(self.surface.phi0(self._edge_points(edge))).max(initial=0.0))
        scale = comm.allreduce(scale, op=MPI.MAX)
        if hi - lo > 1e-9 * scale:
            raise ValueError(
                f"symmetry plane on {edge}: the edge is not in a plane normal to {AXES[axis]} "
                f"({AXES[axis]} spans {lo:.6g} to {hi:.6g} along it)"
            )
        along = [
            comm.allreduce(bool(np.all(np.isclose(np.abs(t[axis]), 1.0))), op=MPI.LAND) for t in (t2, t1)
        ]
        if not any(along):
            raise ValueError(
                f"symmetry plane on {edge}: the plane normal to {AXES[axis]} must contain the shell's "
                "normal, i.e. be normal to the tangent t1 or t2 all along the edge"
            )
        angle = 0 if along[0] else 1
        facets = self._facets(edge)
        self.bcs += [facet_condition(self.model, sub, facets)[1] for sub in ((0, axis), (1, angle))]

    def fix_point(self, point, directions: str = "xyz") -> None:
        """Zero displacement along ``directions`` (any of x, y, z) at the node at ``point``
        (parameter coordinates): a support against rigid motion."""
        if not directions or any(c not in AXES for c in directions):
            raise ValueError(f"fix_point: directions {directions!r} must be made of x, y and z")
        self._require_node(point, "fix_point")
        p = np.asarray(point, dtype=float)

        def at_point(x):
            return np.isclose(x[0], p[0], atol=1e-10 * (1 + abs(p[0]))) & np.isclose(
                x[1], p[1], atol=1e-10 * (1 + abs(p[1]))
            )

        for c in directions:
            space = self.model.W.sub(0).sub(AXES.index(c))
            collapsed, _ = space.collapse()
            dofs = dolfinx.fem.locate_dofs_geometrical((space, collapsed), at_point)
            zero = dolfinx.fem.Function(collapsed)
            self.bcs.append(dolfinx.fem.dirichletbc(zero, dofs, space))

    # --- loads, per unit of the load parameter
    def _add_work(self, work) -> None:
        self.work_per_load = work if self.work_per_load is None else self.work_per_load + work

    def point_force(self, point, force) -> None:
        """A force vector (fixed direction) at the node at ``point``, per unit lambda."""
        self._require_node(point, "point_force")
        for i, component in enumerate(np.asarray(force, dtype=float)):
            if component != 0.0:
                dofs = owned_node_dofs(self.model.W, (0, i), point)
                self.point_forces.append(PointForce(dofs, _PerUnitLoad(self.load, component)))

    def edge_force(self, edge: str, force) -> None:
        """A force per unit (physical) length of the edge, fixed in direction, per unit lambda."""
        f = ufl.as_vector([float(c) for c in force])
        self._add_work(ufl.dot(f, self.model.u) * self._line_element(edge) * self.model.ds(self.edge(edge)))

    def edge_moment(self, edge: str, moment: float, angle: int = 1) -> None:
        """A moment per unit length of the edge, work-conjugate to the director angle ``angle``
        (theta_1: about the tangent t2; theta_0: about t1), per unit lambda.

        Conjugate to an angle, the moment follows the edge as it turns: the roll-up
        cantilever's end moment, which rolls a strip into turns.
        """
        if angle not in (0, 1):
            raise ValueError(f"edge_moment: angle {angle} must be 0 or 1 (theta_0 or theta_1)")
        m = self.model
        self._add_work(float(moment) * m.theta[angle] * self._line_element(edge) * m.ds(self.edge(edge)))

    # --- solve and measure
    def solve(
        self,
        load: float,
        *,
        first_step: float,
        max_step: float,
        min_step: float | None = None,
        stops: tuple[float, ...] = (),
        on_step=None,
        solver_config: SolverConfig | None = None,
        prefix: str | None = None,
    ) -> list[StepRecord]:
        """Step lambda from 0 to ``load`` (adaptive, with cut-back); steps in lambda's units.

        ``stops``: values of lambda stepped onto exactly; ``on_step(record)`` after each
        converged step (``record.load`` is lambda). ``min_step`` defaults to 1e-6 ``load``;
        ``solver_config``: the ``[solver]`` settings (Newton tolerances, cut-back, PETSc options).
        """
        if not (np.isfinite(load) and load > 0):
            raise ValueError(f"solve: load {load} must be positive")
        if not 0 < first_step <= max_step <= load:
            raise ValueError(
                f"solve: steps must satisfy 0 < first_step ({first_step}) <= max_step ({max_step}) "
                f"<= load ({load})"
            )
        settings = solver_config or SolverConfig()
        work = None if self.work_per_load is None else self.load * self.work_per_load
        F = self.model.residual(work)
        solver = SNESSolver.from_config(
            F,
            self.model.jacobian_form(F),
            self.model.q,
            self.bcs,
            settings,
            prefix=prefix or f"{self.name}_",
            state_scale=self.model.rounding_scale(),
        )
        solver.point_forces.extend(self.point_forces)
        smallest = 1e-6 * load if min_step is None else min_step
        control = settings.control(
            initial_step=first_step / load, max_step=max_step / load, min_step=smallest / load
        )

        def set_load(value: float) -> None:
            self.load.value = value

        try:
            return Continuation(solver.solve, set_load, self.model.q, control, on_step=on_step).run(
                0.0, load, stops
            )
        finally:
            solver.destroy()

    def displacement_at(self, point) -> np.ndarray:
        """The displacement (3,) of the node at ``point`` (parameter coordinates), on every rank."""
        self._require_node(point, "displacement_at")
        return np.array([node_value(self.model.q, (0, i), point) for i in range(3)])

    def edge_average(self, edge: str, expression) -> np.ndarray:
        """The average of a vector expression over the edge, by its physical length (collective)."""
        line, ds, comm = self._line_element(edge), self.model.ds(self.edge(edge)), self.strip.mesh.comm
        length = global_scalar(line * ds, comm)
        return np.array(
            [global_scalar(expression[i] * line * ds, comm) / length for i in range(len(expression))]
        )
