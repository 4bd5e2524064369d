"""A beam stated as a benchmark is (:class:`BeamProblem`): line, section, frame, supports (a
clamp, one that turns with the load, a guide), end loads, a rigid hub or turns wound on it,
load steps."""

from __future__ import annotations

import math
from types import SimpleNamespace

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.core import compat, jit
from tapecoil.core.dofs import assemble_into, owned_subspace_dofs
from tapecoil.core.expression import expression_at
from tapecoil.core.newton import PerUnitLoad, PointForce, SNESSolver
from tapecoil.core.rotation import rotation_matrix
from tapecoil.core.smoothing import penetration_ufl
from tapecoil.core.stepping import Continuation, StepRecord
from tapecoil.models.beam import GeometricallyExactBeam, create_beam_mesh, vertices_at

__all__ = ["BeamProblem"]


class BeamProblem:
    """A beam stated as a benchmark is: line, section, frame, supports, loads, load steps.

    ``centre_line(s)`` and ``length``, ``elements``: the mesh (:func:`create_beam_mesh`: a
    length and a count, or spans and a count for each);
    ``section``, ``frame``: see :class:`GeometricallyExactBeam`. Loads are given per unit of a load
    parameter (or held constant), and :meth:`solve` steps the parameter; a clamp may turn with it
    as an angle. ``name``: the PETSc options prefix is ``name + "_"``.
    """

    def __init__(self, centre_line, length, elements, section, frame, *, comm=MPI.COMM_WORLD, name="beam"):
        self.mesh = create_beam_mesh(comm, centre_line, length, elements)
        self.mesh.topology.create_connectivity(0, 1)
        self.model = GeometricallyExactBeam(self.mesh, section, frame)
        self.name = name
        self.load = dolfinx.fem.Constant(self.mesh, 0.0)  # the load parameter
        self.committed_load = 0.0  # the load parameter of the last accepted step
        self.bcs: list = []
        self.point_forces: list[PointForce] = []
        self.energy_terms: list = []  # UFL energies beside the beam's own (contact)
        # (u function or None, theta function, point, axis point, axis, place at load 0): nodes
        # turned by the load
        self._turning: list[tuple] = []
        self._winding: list = []  # the winding contacts' updates of their angles
        self._winding_angles: list = []  # (angles, their nodes' reference points, update)
        self._predictors: list = []  # initial guesses of a step: predict(load_from, load_to)
        self.history: list[StepRecord] = []

    def _vertices(self, point) -> np.ndarray:
        return vertices_at(self.mesh, point)

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

    def clamp(self, point, turning_about: tuple | None = None, at=None) -> None:
        """Hold the node at ``point`` [m]: its displacement and rotation. ``turning_about`` =
        (a point of the axis [m], the axis's direction): the clamp turns about that axis by the
        load parameter [rad] (a hub that the beam's root is fixed to). ``at``: where the node is
        held at load 0 [m] (default ``point``; a flattened tape's line, which lies off its arc's
        centroid line)."""
        vertices = self._vertices(point)
        u_values = self._dirichlet((0,), vertices)
        theta_values = self._dirichlet((1,), vertices)
        point = np.asarray(point, dtype=float)
        place = point if at is None else np.asarray(at, dtype=float)
        if turning_about is not None:
            centre, axis = (np.asarray(v, dtype=float) for v in turning_about)
            axis = axis / np.linalg.norm(axis)
            self._turning.append((u_values, theta_values, point, centre, axis, place))
        else:
            u_values.x.array[:] = np.tile(place - point, len(u_values.x.array) // 3)

    def turn(self, point, axis) -> None:
        """Turn the node at ``point`` [m] by the load parameter [rad] about ``axis``, its
        displacement free: a rigid end section turned, which carries a pure moment."""
        a = np.asarray(axis, dtype=float)
        theta_values = self._dirichlet((1,), self._vertices(point))
        point = np.asarray(point, dtype=float)
        self._turning.append((None, theta_values, point, None, a / np.linalg.norm(a), point))

    def hold(self, point, components: tuple[int, ...], rotation: bool | tuple[int, ...] = False) -> None:
        """Hold the displacement components ``components`` (0, 1, 2: x, y, z) of the node at
        ``point`` at zero (a guide the node slides along) and, with ``rotation``, its rotation:
        True all of it, a tuple of axes (0, 1, 2: x, y, z) its turning about those alone (the
        node then turns about the others' complement, a fixed axis)."""
        vertices = self._vertices(point)
        for i in components:
            self._dirichlet((0, i), vertices)
        if rotation is True:
            self._dirichlet((1,), vertices)
        elif rotation:
            for i in rotation:
                self._dirichlet((1, i), vertices)

    def end_load(self, point, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0), *, constant=False) -> None:
        """A force [N] and a moment [N m] on the node at ``point``, per unit load parameter (or,
        ``constant``, as given at every load), both of fixed direction (dead loads); the moment
        does work on the spatial rotation, exactly so when it keeps its axis (plane bending)."""
        vertices = self._vertices(point)
        for sub, vector in ((0, force), (1, moment)):
            for i, value in enumerate(vector):
                if value != 0.0:
                    dofs = owned_subspace_dofs(self.model.W, (sub, i), 0, vertices)
                    magnitude = (
                        SimpleNamespace(value=float(value)) if constant else PerUnitLoad(self.load, value)
                    )
                    self.point_forces.append(PointForce(dofs, magnitude))

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

    def winding_contact(
        self,
        axis_point,
        axis,
        reference,
        obstacle,
        penalty: float,
        smoothing: float = 0.0,
        half_width=None,
    ) -> dolfinx.fem.Function:
        """Keep the beam's line out of a cylinder about the axis through ``axis_point`` along
        ``axis`` whose radius depends on how far each point has been wound round it:
        ``obstacle(psi)`` [m] (UFL), the energy (k/2) <obstacle(psi) - distance>^2 per unit
        length, k = ``penalty`` [N/m^2], the bracket smoothed over ``smoothing`` [m] as the
        shell's (:func:`~tapecoil.core.smoothing.penetration_ufl`). Turns resting on turns (a
        spiral obstacle, as the shell's ``contact.turns = "spiral"``).

        With ``half_width(x)`` [m] (numpy, of the cells' midpoints' reference coordinate along
        the tape), a flat section of that half width rests on the obstacle instead of its line:
        the energy is taken across the section, along its axis 2, by Simpson's rule (its edges
        a sixth each, the line two thirds), as the shell's contact is taken across the strip. A
        line alone does not feel its section turn about it; a flat strip whose edges dig into
        the turn beneath does (where the half width is 0 the line's energy is as above).

        psi, the winding angle [rad], is the load parameter (the hub angle of a clamp turning
        about this axis) less the node's swept angle, measured about the axis in its right-hand
        sense from ``reference`` (a direction from the axis: the root's at load 0). It is read
        from the state after every accepted step and unwrapped continuously (a node moves less
        than half a turn a step), so the nodes of successive turns keep their turn; within a
        step it is held, and the obstacle's force is radial. Each step starts with the nodes
        wound more than a radian behind the lift-off turned about the axis by the step of the
        load parameter, as a rigid body with the hub. Returns psi (at the line's nodes).
        """
        if not (math.isfinite(penalty) and penalty > 0):
            raise ValueError(f"winding contact: the penalty must be a positive number, got {penalty!r}")
        centre = np.asarray(axis_point, dtype=float)
        a = np.asarray(axis, dtype=float)
        a = a / np.linalg.norm(a)
        e0 = np.asarray(reference, dtype=float)
        e0 = e0 - np.dot(e0, a) * a
        e0 = e0 / np.linalg.norm(e0)
        components = [compat.collapse(self.model.W.sub(0).sub(i)) for i in range(3)]
        space = components[0][0]
        psi = dolfinx.fem.Function(space, name="winding_angle")
        nodes = space.tabulate_dof_coordinates()[:, :3]
        maps = [m for _, m in components]
        # the rotation's components at the same nodes (the collapsed spaces share their layout)
        rotation_maps = [compat.collapse(self.model.W.sub(1).sub(i))[1] for i in range(3)]

        def swept() -> np.ndarray:
            q = self.model.q.x.array
            p = nodes + np.column_stack([q[m] for m in maps]) - centre
            radial = p - np.outer(p @ a, a)
            return np.arctan2(radial @ np.cross(a, e0), radial @ e0)

        def update() -> None:
            raw = self.committed_load - swept()
            psi.x.array[:] += (raw - psi.x.array + math.pi) % (2 * math.pi) - math.pi

        def predict(load_from: float, load_to: float) -> None:
            # the wound nodes (a radian behind the lift-off) turn with the hub as a rigid body:
            # without it Newton has to carry the whole coil round, and fails as nodes meet the
            # obstacle
            wound = psi.x.array < load_from - 1.0
            if not wound.any():
                return
            q = self.model.q.x.array
            p = nodes[wound] + np.column_stack([q[m[wound]] for m in maps]) - centre
            moved = p @ rotation_matrix(a, load_to - load_from).T + centre - nodes[wound]
            for i in range(3):
                q[maps[i][wound]] = moved[:, i]
                q[rotation_maps[i][wound]] += (load_to - load_from) * a[i]

        psi.x.array[:] = self.committed_load - swept()
        self._winding.append(update)
        self._winding_angles.append((psi, nodes, update))
        self._predictors.append(predict)
        line = ufl.SpatialCoordinate(self.mesh) + self.model.u - ufl.as_vector(centre.tolist())
        av = ufl.as_vector(a.tolist())

        def penetration(point):
            radial = point - ufl.dot(point, av) * av
            return penetration_ufl(obstacle(psi) - ufl.sqrt(ufl.dot(radial, radial)), smoothing)

        if half_width is None:
            density = penetration(line) ** 2
        else:
            widths = dolfinx.fem.Function(dolfinx.fem.functionspace(self.mesh, ("DG", 0)), name="half_width")
            cells = np.arange(self.mesh.topology.index_map(1).size_local, dtype=np.int32)
            middle = dolfinx.mesh.compute_midpoints(self.mesh, 1, cells)[:, 0]
            dofs = np.asarray(widths.function_space.dofmap.list)[cells].reshape(-1)
            widths.x.array[dofs] = np.asarray(half_width(middle), dtype=float)
            widths.x.scatter_forward()
            across = widths * ufl.as_vector([self.model.frame[i, 1] for i in range(3)])
            density = (
                penetration(line - across) ** 2 + 4 * penetration(line) ** 2 + penetration(line + across) ** 2
            ) / 6
        self.energy_terms.append(0.5 * penalty * density * self.model.dx)
        return psi

    def add_predictor(self, predict) -> None:
        """Another initial guess of each step, ``predict(load_from, load_to)``, which sets the
        state from the converged one (after the winding contacts' own)."""
        self._predictors.append(predict)

    def slide(self, beyond: float, along) -> None:
        """Predict each step by sliding the nodes beyond ``beyond`` [m] along the tape by
        ``along(load_from, load_to)`` [m] in -x: a straight part that runs towards a hub at the
        length it winds on (its frames kept)."""
        dofs = self.model.node_u_dofs[self.model.node_points[:, 0] > beyond, 0]

        def predict(load_from: float, load_to: float) -> None:
            self.model.q.x.array[dofs] -= along(load_from, load_to)

        self.add_predictor(predict)

    def set_winding(self, estimate) -> None:
        """The winding angles of every winding contact from ``estimate(x)`` [rad] (numpy, x the
        nodes' reference coordinate along the tape), each node then put on the branch of its
        angle nearest the estimate at the present state and load (a state carried over from
        another model of the tape, whose angles the estimate gives to within half a turn)."""
        for psi, nodes, update in self._winding_angles:
            psi.x.array[:] = estimate(nodes[:, 0])
            update()

    def state_fields(self) -> dict:
        """The beam's state fields (:meth:`GeometricallyExactBeam.state_fields`) and its winding
        contacts' angles, as cell fields."""
        from tapecoil.core.cell_state import function_field

        fields = {f"model/{name}": field for name, field in self.model.state_fields().items()}
        for i, (psi, _, _) in enumerate(self._winding_angles):
            fields[f"winding{i}"] = function_field(psi)
        return fields

    def state_values(self) -> dict:
        """The scalars of the state: the accepted load parameter and the natural curvatures' share."""
        return {"committed_load": self.committed_load, "natural_share": float(self.model.natural_share.value)}

    def set_state_values(self, values: dict) -> None:
        """Put back :meth:`state_values` (after the fields), the loads set to the accepted one."""
        self.committed_load = float(values["committed_load"])
        self.model.natural_share.value = float(values["natural_share"])
        self.set_load(self.committed_load)

    def forms(self) -> tuple:
        """The residual and Jacobian (UFL) of the beam's energy and the energies beside it."""
        model = self.model
        energy = model.energy + sum(self.energy_terms)
        residual = ufl.derivative(energy, model.q, model.dq)
        return residual, ufl.derivative(residual, model.q, ufl.TrialFunction(model.W))

    def set_load(self, value: float) -> None:
        """The load parameter, and the supports it turns, in place (a driver of its own, the
        arc-length continuation, sets it so)."""
        self.load.value = value
        for u_values, theta_values, point, centre, axis, place in self._turning:
            if u_values is not None:
                R = rotation_matrix(axis, value)
                u = R @ (place - centre) + centre - point
                u_values.x.array[:] = np.tile(u, len(u_values.x.array) // 3)
            increment = (value - self.committed_load) * axis  # the rotation since the last accepted step
            theta_values.x.array[:] = np.tile(increment, len(theta_values.x.array) // 3)

    def predict(self, load_from: float, load_to: float) -> None:
        """The initial guess of a step from ``load_from`` to ``load_to``: each predictor's."""
        for predict in self._predictors:
            predict(load_from, load_to)

    def commit(self) -> None:
        """Accept the state in place as a converged step: the rotations' reference moves on."""
        self.model.commit()
        self.committed_load = float(self.load.value)
        for update in self._winding:
            update()
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
        residual, jacobian = self.forms()
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
            set_load=self.set_load,
            state=model.q,
            control=control,
            commit=self.commit,
            on_step=on_step,
            predict=self.predict if self._predictors else None,
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
        force = expression_at(model.section_fields[0] * model.strain[0], points).eval(self.mesh, cells)
        where = expression_at(ufl.SpatialCoordinate(self.mesh), points).eval(self.mesh, cells)
        comm = self.mesh.comm
        x = np.concatenate(comm.allgather(where.reshape(-1, 3)))
        N = np.concatenate(comm.allgather(force.reshape(-1)))
        return x, N

    def internal_force(self, point) -> np.ndarray:
        """The force [N] that the beam's energy and the energies beside it (contact) put on the
        node at ``point``, dE/du there: the load its support carries (collective)."""
        if getattr(self, "_internal_form", None) is None:
            energy = self.model.energy + sum(self.energy_terms)
            self._internal_form = jit.form(ufl.derivative(energy, self.model.q, self.model.dq))
            self._internal_vector = dolfinx.fem.Function(self.model.W)
        f = assemble_into(self._internal_vector, self._internal_form)
        vertices = self._vertices(point)
        local = np.array([f[owned_subspace_dofs(self.model.W, (0, i), 0, vertices)].sum() for i in range(3)])
        return self.mesh.comm.allreduce(local, op=MPI.SUM)

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
