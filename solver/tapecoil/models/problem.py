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

import time

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.config import SolverConfig
from tapecoil.core.dofs import global_scalar, node_value, owned_node_dofs
from tapecoil.core.newton import PerUnitLoad, PointForce, SNESSolver
from tapecoil.core.stepping import Continuation, StepRecord
from tapecoil.geometry.meshes import EDGE_NAMES, MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import Surface
from tapecoil.models.edges import EdgeMotion, clamp, hinge
from tapecoil.models.shell import NaghdiShell, ShellMaterial
from tapecoil.models.supports import fixed_point, symmetry_plane

# the edges by name (the names of the mesh's physical groups for a general surface)
EDGES = {name: tag for tag, name in EDGE_NAMES.items()}


class ShellProblem:
    """A Naghdi shell (:class:`NaghdiShell`, Q2, PSRI by default) on ``surface``, meshed at
    ``resolution``, with supports and loads added by the methods below before :meth:`solve`.

    ``name``: the PETSc options prefix of its solver is ``name + "_"`` (unless ``solve`` is
    given another ``prefix``); any PETSc option for it
    is given on the command line of the script that solves it, ``python3 my_script.py
    -shell_snes_monitor`` with the default name, and wins over ``solve``'s settings;
    ``director_frame``: the director's frame, ``"global"`` for tapes (see :mod:`~tapecoil.models.shell`).
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
        director_frame: str = "local",
    ):
        surface.check()
        self.surface = surface
        self.strip = create_strip_mesh(comm, surface, resolution)
        self.model = NaghdiShell(self.strip, material, technology, director_frame=director_frame)
        self.name = name
        self.load = dolfinx.fem.Constant(self.strip.mesh, 0.0)  # lambda, the load parameter
        self.bcs: list = []
        self.work_per_load = None  # UFL form: the external work of the loads per unit lambda
        self.point_forces: list[PointForce] = []
        self._motions: list[EdgeMotion] = []  # edges turned by the load parameter
        # of the last solve, every attempt counted (the ones cut back, and a step that never
        # converged): its wall time [s], Newton iterations, and the solver's timings
        # (:attr:`SNESSolver.timings`); each step's own are in its StepRecord
        self.wall_time = 0.0
        self.newton_iterations = 0
        self.timings: dict = {}

    # --- where things are
    def edge(self, name: str) -> int:
        """The facet tag of the edge ``name``."""
        if name not in EDGES:
            raise ValueError(f"edge {name!r}: one of {', '.join(EDGES)} (the parameter bound it lies on)")
        return EDGES[name]

    def _facets(self, edge: str) -> np.ndarray:
        return self.strip.facet_tags.find(self.edge(edge))

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

    def hinge(self, edge: str) -> None:
        """The edge held in place, free to turn: zero displacement, the director free."""
        self.bcs += hinge(self.model, self.edge(edge))

    def turn(self, edge: str, axis, axis_point) -> None:
        """The edge held, turned rigidly by the load parameter [rad] about the line through
        ``axis_point`` along ``axis`` [m] (a clamp on a turning hub)."""
        motion = EdgeMotion(
            self.model, self.edge(edge), np.asarray(axis, dtype=float), np.asarray(axis_point, dtype=float)
        )
        self.bcs += motion.bcs
        self._motions.append(motion)

    def set_load(self, value: float) -> None:
        """The load parameter lambda, and the turned edges' angles with it."""
        self.load.value = value
        for motion in self._motions:
            motion.set(value)

    def commit(self, load: float) -> None:
        """After an accepted step at the load parameter ``load``: nothing here; a problem that
        keeps state read from the converged one (a hub's winding angles) updates it."""

    def predict(self, load_from: float, load_to: float) -> None:
        """The initial guess of a step from ``load_from`` to ``load_to``: the converged state as
        it is here; a problem that knows better (material turning with a hub) sets it."""

    def symmetry_plane(self, edge: str, normal) -> None:
        """The edge lies on a plane of symmetry with unit ``normal`` (+-x, +-y or +-z): see
        :func:`~tapecoil.models.supports.symmetry_plane`.

        The model is then part of the whole shell, and a load lying on the plane is shared
        with the part cut away: give the model its share. A point force on the plane is halved
        (P/2 for the whole's P; P/4 at a point on two planes, a quarter model), and so is a
        force along an edge that lies on the plane; a load off the plane, or along an edge
        that crosses it, is the whole's own (the cut edge carries half of its length). The
        loads are stated per model, not per whole shell: nothing here halves them.
        """
        self.bcs += symmetry_plane(self.model, self._facets(edge), normal, edge)

    def fix_point(self, point, directions: str = "xyz") -> None:
        """Zero displacement along ``directions`` (any of x, y, z) at the node at ``point``
        (parameter coordinates): a support against rigid motion."""
        self._require_node(point, "fix_point")
        self.bcs += fixed_point(self.model, point, directions)

    # --- loads, per unit of the load parameter
    def _add_work(self, work) -> None:
        self.work_per_load = work if self.work_per_load is None else self.work_per_load + work

    def point_force(self, point, force) -> None:
        """A force vector (fixed direction) at the node at ``point``, per unit lambda.

        At a point on a plane of symmetry (:meth:`symmetry_plane`) the force is the model's
        share of the whole shell's: half of it (a quarter on two planes), as for Sze's pinched
        semicylinder modelled by its half, loaded by P/2."""
        self._require_node(point, "point_force")
        for i, component in enumerate(np.asarray(force, dtype=float)):
            if component != 0.0:
                dofs = owned_node_dofs(self.model.W, (0, i), point)
                self.point_forces.append(PointForce(dofs, PerUnitLoad(self.load, component)))

    def edge_force(self, edge: str, force) -> None:
        """A force per unit (physical) length of the edge, fixed in direction, per unit lambda.

        On an edge that lies on a plane of symmetry (:meth:`symmetry_plane`) it is the model's
        share of the whole's line force there: half of it."""
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
    def forms(self) -> tuple:
        """The residual and Jacobian (UFL) of the shell under its loads at the load parameter."""
        work = None if self.work_per_load is None else self.load * self.work_per_load
        F = self.model.residual(work)
        return F, self.model.jacobian_form(F)

    def snes_solver(self, settings: SolverConfig, prefix: str | None = None, options: dict | None = None):
        """The Newton solver of this problem's forms, Dirichlet conditions and point forces, with
        the ``[solver]`` ``settings`` and the problem's own PETSc ``options`` under ``prefix``
        (default: the problem's name). The caller destroys it."""
        F, J = self.forms()
        solver = SNESSolver.from_config(
            F,
            J,
            self.model.q,
            self.bcs,
            settings,
            prefix=prefix or f"{self.name}_",
            defaults=options,
            state_scale=self.model.rounding_scale(),
        )
        solver.point_forces.extend(self.point_forces)
        return solver

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
        options: dict | None = None,
    ) -> list[StepRecord]:
        """Step lambda from 0 to ``load`` (adaptive, with cut-back); steps in lambda's units.

        ``stops``: values of lambda stepped onto exactly; ``on_step(record)`` after each
        converged step (``record.load`` is lambda). ``min_step`` defaults to 1e-6 ``load``;
        ``solver_config``: the ``[solver]`` settings (Newton tolerances, cut-back, PETSc options);
        ``options``: the problem's own PETSc options (without prefix), under those settings'.
        Returns a :class:`~tapecoil.core.stepping.StepRecord` per converged step: its
        ``iterations`` are the accepted attempt's, its ``total_iterations`` every attempt's.
        Afterwards (also after a failure) :attr:`newton_iterations` and :attr:`wall_time` hold
        the whole solve's, every attempt counted.
        """
        if not (np.isfinite(load) and load > 0):
            raise ValueError(f"solve: load {load} must be positive")
        if not 0 < first_step <= max_step <= load:
            raise ValueError(
                f"solve: steps must satisfy 0 < first_step ({first_step}) <= max_step ({max_step}) "
                f"<= load ({load})"
            )
        settings = solver_config or SolverConfig()
        solver = self.snes_solver(settings, prefix, options)
        smallest = 1e-6 * load if min_step is None else min_step
        control = settings.control(
            initial_step=first_step / load, max_step=max_step / load, min_step=smallest / load
        )

        t0 = time.perf_counter()
        try:
            return Continuation(
                solver.solve,
                self.set_load,
                self.model.q,
                control,
                on_step=on_step,
                commit=lambda: self.commit(float(self.load.value)),
            ).run(0.0, load, stops)
        finally:
            self.wall_time = time.perf_counter() - t0
            self.timings = dict(solver.timings)
            self.newton_iterations = int(solver.timings["iterations"])
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
