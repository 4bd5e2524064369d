"""Dynamic deployment of the stowed tape: implicit generalized-alpha from the coiled state.

At release (physics.md Sec. 6, thesis Table 3.2) the pull and the guide at the free end are
removed, the hub is held at its final angle and the root stays attached to it; hub and
coil-on-coil contact are kept. The stored strain energy drives the free part round the hub,
peeling the tape off the coil (Seffen and Pellegrino's picture: a straight part tangent to the
coil, which shrinks).

Inertia is the shell's consistent one, translational and rotary
(:mod:`tapecoil.phases.deployment_forms`). Time stepping is generalized-alpha
(:mod:`tapecoil.core.timeint`) with adaptive steps and the cut-back logic of the load stepping
(:class:`tapecoil.core.stepping.Continuation`).

The deployed fraction lambda is measured from the geometry
(:func:`tapecoil.measures.deployment.lift_off`).
"""

from __future__ import annotations

from pathlib import Path

import dolfinx
import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil.config import Config
from tapecoil.core import checkpoint, jit
from tapecoil.core.checkpoint import state_parts
from tapecoil.core.dofs import assemble_into, global_dot, global_scalar, owned_constrained_dofs, owned_size
from tapecoil.core.newton import SNESSolver
from tapecoil.core.timeint import GeneralizedAlpha
from tapecoil.geometry.meshes import FREE_END
from tapecoil.hub.rotor import HubRotor
from tapecoil.measures.deployment import lift_off
from tapecoil.phases.deployment_forms import DeploymentForms, director_rates  # noqa: F401 - re-exported
from tapecoil.phases.free_hub import FreeHubCoupling
from tapecoil.phases.release import EndHold
from tapecoil.phases.root_loads import RootLoads
from tapecoil.phases.tape_on_hub import TapeOnHub
from tapecoil.phases.time_loop import step_error


class DeploymentProblem:
    """The released tape: root attached to the hub, contact kept, inertia added.

    The hub is held at its stowed angle (``deployment.hub = "fixed"``) or turns on its axis with
    the rotary inertia ``hub.inertia`` (``"free"``: :mod:`tapecoil.phases.free_hub`).

    ``tape`` is a :class:`TapeOnHub` in the stowed state (a coiling run's, or read from a
    checkpoint of either phase); its shell, contact and root attachment are reused.
    ``config`` (default: the tape's) sets the deployment; ``rho_inf`` overrides its spectral
    radius.
    """

    def __init__(self, tape: TapeOnHub, config: Config | None = None, rho_inf: float | None = None):
        self.tape = c = tape
        self.config = cfg = config or tape.config
        self.comm = c.comm
        self.model = model = c.model
        self.contact = c.contact
        self._stowed_angle = c.root.angle
        c.root.set(1.0, self._stowed_angle)
        c.contact.turn(self._stowed_angle)
        self.bcs = c.root.bcs
        tp = cfg.tape
        self.rho_inf = cfg.deployment.rho_inf if rho_inf is None else rho_inf
        self.integrator = ti = GeneralizedAlpha(model.q, self.rho_inf)

        # the hub's friction (contact.hub_friction) at the step's end, in either scheme: it
        # dissipates, and its return mapping is a backward Euler step
        friction = c.friction_residual()
        self.forms = forms = DeploymentForms(model, ti, c.contact, tp, friction=friction)

        # the hold on the free end (the guide and the pull of the coiling run), let go over
        # release_time (phases.release)
        self.hold = EndHold(c, ti, cfg.deployment.release_time)
        # the loads on the tape: the hold, and gravity (a ground test; zero in orbit), a Constant
        # in the forms whatever its value, so that a run with gravity and one without share
        # every compiled form (a term of the residual changes the Jacobian's signature too)
        self.gravity = np.asarray(cfg.deployment.gravity, dtype=float)
        g = dolfinx.fem.Constant(model.mesh, self.gravity)
        self.weight = forms.weight(g)  # its virtual work, a UFL form (the root loads take it too)
        self._weight = jit.form(self.weight)
        self._weight_work = jit.form(forms.weight_work(g))
        loads = self.hold.form - self.weight
        if friction is not None:
            loads = loads + friction

        self.scheme = "conserving" if self.rho_inf == 1.0 else "alpha"
        if self.scheme == "alpha":
            F, J, kinetic = forms.alpha(loads)
            options = {"pc_type": "cholesky"}
        else:
            F, J, kinetic = forms.conserving(loads)
            options = {}
        self.solver = SNESSolver.from_config(
            F,
            J,
            model.q,
            self.bcs,
            cfg.deployment.newton(cfg.solver),
            prefix="deploy_",
            defaults={**options, **self.tape.solver_options()},
            options=cfg.deployment.petsc_options,
            state_scale=model.rounding_scale(),
        )
        self.kinetic_form = jit.form(kinetic * model.jacobian * model.dx)
        self.solver.point_forces.append(self.hold.point_force())
        # the turns' contact force at the level of the other internal forces: generalized-alpha's
        # average, and for rho_inf = 1 the trapezoidal mean of the two states (not a discrete
        # gradient: the penalty of the turns is the one force of the conserving scheme that is
        # only conserving to the order of the step)
        alpha_f = ti.parameters.alpha_f if self.scheme == "alpha" else 0.5
        self.solver.terms += c.contact_terms(model.q, self.bcs, 1.0 - alpha_f, (alpha_f, ti.q_old))
        self._tip_forms = [jit.form(model.phi[i] / tp.b * model.ds(FREE_END)) for i in range(3)]
        self.root_loads = RootLoads(self)
        self._angular_momentum = jit.form(forms.angular_momentum(c.frame) * model.jacobian * model.dx)
        self.rotor = self.coupling = None
        if cfg.deployment.hub == "free":
            self.rotor = HubRotor(cfg.hub.inertia, ti.parameters, self._stowed_angle)
            self.coupling = FreeHubCoupling(self, self.rotor, J)
        u_dofs = c.contact.nodes.u_dofs.ravel()
        self._owned_u_dofs = np.unique(u_dofs[u_dofs < owned_size(model.W)])

    @property
    def hub_angle(self) -> float:
        """The hub's angle at the last converged time [rad] (coiling sense)."""
        return self._stowed_angle if self.rotor is None else self.rotor.angle

    def solve(self):
        """The step's nonlinear solve: the tape's, with the free hub's equation if it turns."""
        return self.solver.solve() if self.coupling is None else self.coupling.solve()

    def predict(self, dt: float) -> None:
        """The step's first guess (constant velocities), the hub's included."""
        self.integrator.predict(dt)
        if self.rotor is not None:
            self.rotor.predict(dt)
            self.coupling.place(self.rotor.new_angle)

    def hub_state(self) -> dict:
        """The free hub's restart state (nothing for a fixed hub)."""
        return {} if self.rotor is None else self.rotor.state()

    def restore_hub(self, state: dict) -> None:
        if self.rotor is not None:
            self.rotor.restore(state)
            self.coupling.place(self.rotor.angle)

    def restore(self, path: str | Path) -> None:
        """Velocity, acceleration, the stowed state and the director velocity from a checkpoint
        written by :func:`write_deployment_checkpoint` (the state itself is already in place)."""
        ti, W = self.integrator, self.model.W
        parts = {}
        for prefix in ("velocity_", "acceleration_", "stowed_"):
            parts.update(checkpoint.empty_state_parts(W, prefix))
        extra = {"director_rate": self.forms.director_rate} if self.scheme == "conserving" else {}
        checkpoint.read_functions(path, {**parts, **extra})
        checkpoint.set_state(ti.v_old, parts, "velocity_")
        checkpoint.set_state(ti.a_old, parts, "acceleration_")
        checkpoint.set_state(self.hold.stowed, parts, "stowed_")
        # the hold's dead forces are what held the end in the stowed state
        self.hold.restore_stowed()
        ti.restart()

    def step_work(self) -> float:
        """The external loads' work on the tape over the step just solved [J] (collective; before
        :meth:`advance`): the releasing hold's, and gravity's."""
        work = self.hold.work()
        if np.any(self.gravity):
            work += global_scalar(self._weight_work, self.comm)
        return work

    def residual_work(self) -> float:
        """The converged residual's work over the step just solved [J] (collective; before
        :meth:`advance`): what the Newton tolerance leaves in the step's energy balance."""
        step = self.model.q.x.array - self.integrator.q_old.x.array
        return global_dot(self.model.W, self.solver.b.array, step)

    def step_error(self) -> float:
        """The step's local error over its tolerance (:func:`~tapecoil.phases.time_loop.step_error`
        of the translational dofs; collective; before :meth:`advance`)."""
        parts = [(self.integrator, self._owned_u_dofs)]
        return step_error(parts, self.config.deployment.error_tolerance, self.config.tape.h, self.comm)

    def advance(self) -> None:
        """After a converged step: the new state, velocities and accelerations become the old."""
        if self.scheme == "conserving":  # before q_old moves on
            self.forms.advance_director_rate()
        self.integrator.advance()
        if self.rotor is not None:
            self.rotor.advance()

    # -- start ----------------------------------------------------------------------------------
    def initial_acceleration(self) -> None:
        """Translational a_0 from M a_0 = f_hold + f_gravity - f_int(q_0), at rest.

        At t = 0 the hold still balances the internal forces, so without gravity a_0 is the
        solver's residual noise; it is computed rather than assumed. The mass matrix at rest (no
        centripetal term) is solved with a direct solver; the attached root has zero acceleration.
        """
        model, ti = self.model, self.integrator
        M = dolfinx.fem.petsc.assemble_matrix(jit.form(self.forms.mass_at_rest()), bcs=self.bcs)
        M.assemble()
        internal = dolfinx.fem.Function(model.W)
        assemble_into(internal, jit.form(self.forms.static))
        self.tape.add_self_contact_force(internal)
        b = internal.x.petsc_vec.copy()
        b.scale(-1.0)
        b.array[self.hold.end_dofs] += self.hold.dead_full
        if np.any(self.gravity):
            weight = dolfinx.fem.Function(model.W)
            assemble_into(weight, self._weight)
            b.axpy(1.0, weight.x.petsc_vec)
        b.array[owned_constrained_dofs(model.W, self.bcs)] = 0.0
        ksp = PETSc.KSP().create(self.comm)
        ksp.setOperators(M)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        x = b.duplicate()
        ksp.solve(b, x)
        ti.a_old.x.array[: x.getLocalSize()] = x.array
        ti.a_old.x.scatter_forward()
        # the rotary part starts from zero: releasing the guide's end moment on the tiny rotary
        # inertia (rho h^3/12) is a transient of nanoseconds, which the predictor would
        # extrapolate into radians; the mass matrix has no u-theta coupling at rest, so the
        # translational part is the consistent one regardless
        ti.a_old.x.array[self.contact.nodes.theta_dofs.ravel()] = 0.0
        if self.rotor is not None and self.rotor.inertia > 0:
            # the free hub starts under the torque the tape held it with (the coiling's)
            rates, _ = self.coupling.root_rates(self.rotor.angle)
            self.rotor.acceleration = -global_dot(model.W, rates, internal.x.array) / self.rotor.inertia
        ti.v_old.x.array[:] = 0.0
        ti.restart()
        for obj in (ksp, M, b, x):
            obj.destroy()

    # -- measures -------------------------------------------------------------------------------
    def energies(self) -> dict[str, float]:
        """The tape's energies, and the kinetic energy of the tape and the hub (``hub_kinetic``)."""
        out = self.tape.energies()
        out["hub_kinetic"] = 0.0 if self.rotor is None else self.rotor.kinetic_energy()
        out["kinetic"] = global_scalar(self.kinetic_form, self.model.mesh.comm) + out["hub_kinetic"]
        return out

    def step_energy(self) -> float:
        """The tape's and the hub's energy (strain, contact, kinetic) at the end of the step
        just solved, its rates as :meth:`advance` will take them [J] (collective; before it)."""
        ti = self.integrator
        saved = ti.v_old.x.array.copy()
        rate = None if self.scheme != "conserving" else self.forms.director_rate.x.array.copy()
        try:
            ti.v_old.x.array[:] = ti.new_rates()[0]
            if rate is not None:
                self.forms.advance_director_rate()
            kinetic = global_scalar(self.kinetic_form, self.comm)
        finally:
            ti.v_old.x.array[:] = saved
            if rate is not None:
                self.forms.director_rate.x.array[:] = rate
        if self.rotor is not None:
            kinetic += 0.5 * self.rotor.inertia * self.rotor.new_rates()[0] ** 2
        e = self.tape.energies()
        return e["strain"] + e["contact"] + e["friction"] + kinetic

    def angular_momentum(self) -> float:
        """Angular momentum about the hub's axis of the tape and the hub [kg m^2/s] (collective;
        from the velocities of the last converged time): a free hub and a released tape keep
        it, since nothing outside them turns them (the hub's contact is radial)."""
        tape = global_scalar(self._angular_momentum, self.model.mesh.comm)
        return tape + (0.0 if self.rotor is None else self.rotor.angular_momentum())

    def tip(self) -> np.ndarray:
        """Mean position of the free end [m] (3,)."""
        return np.array([global_scalar(f, self.model.mesh.comm) for f in self._tip_forms])

    def lift_off(self) -> dict[str, float]:
        """The coiled length and the deployed fraction lambda (:func:`measures.deployment.lift_off`)."""
        return lift_off(self.tape)

    def update(self) -> float:
        """After a converged step: winding angles from the new state (the hub stays put).

        Returns the change of the contact energy the update makes [J] (collective): the
        obstacle between the turns follows the winding angles, which move only between steps.
        """
        before = self.tape.contact_energy()
        self.contact.update(self.hub_angle)
        self.tape.accept_state()
        return self.tape.contact_energy() - before


def write_deployment_checkpoint(model: DeploymentProblem, path: str | Path, meta: dict) -> None:
    """The deployment's restart state: the shell state and winding angles (as a coiling
    checkpoint, so that ``tapecoil deploy`` can start from it too), velocity, acceleration, the
    stowed state the release refers to and, for the conserving scheme, the director velocity."""
    ti = model.integrator
    functions = {
        **state_parts(ti.v_old, "velocity_"),
        **state_parts(ti.a_old, "acceleration_"),
        **state_parts(model.hold.stowed, "stowed_"),
    }
    if model.scheme == "conserving":
        functions["director_rate"] = model.forms.director_rate
    model.tape.write_checkpoint(path, meta, functions)


def read_deployment_checkpoint(path: str | Path, config: Config, comm=MPI.COMM_WORLD):
    """A :class:`DeploymentProblem` in the state of :func:`write_deployment_checkpoint`, and the meta."""
    tape, meta = TapeOnHub.read_checkpoint(path, config, comm)
    model = DeploymentProblem(tape, config)
    model.restore(path)
    return model, meta
