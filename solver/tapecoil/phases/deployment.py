"""Dynamic deployment of the stowed tape: implicit generalized-alpha from the coiled state.

At release (physics.md Sec. 6, thesis Table 3.2) the pull and the guide at the free end are
removed, the hub is held at its final angle and the root stays attached to it; hub and
coil-on-coil contact are kept. The stored strain energy drives the free part round the hub,
peeling the tape off the coil (Seffen and Pellegrino's picture: a straight part tangent to the
coil, which shrinks).

Inertia is the shell's consistent one. With the director d(theta), the kinetic energy per unit
reference area is rho h |u'|^2 / 2 + rho h^3 / 24 |d'|^2; its Euler-Lagrange term in the
direction (du, dtheta) is rho h u''.du + rho h^3/12 d''.(Dd dtheta), with
d'' = Dd theta'' + D^2d[theta', theta'] (the centripetal part of the rotary inertia). Both are
written with UFL's automatic differentiation of d(theta). Time stepping is generalized-alpha
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
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil.config import Config
from tapecoil.core import checkpoint, compat
from tapecoil.core.checkpoint import state_parts
from tapecoil.core.dofs import global_scalar
from tapecoil.core.newton import SNESSolver
from tapecoil.core.timeint import GeneralizedAlpha
from tapecoil.geometry.meshes import FREE_END
from tapecoil.measures.deployment import lift_off
from tapecoil.models.shell import director_from_angles
from tapecoil.phases.release import EndHold, split_state
from tapecoil.phases.tape_on_hub import TapeOnHub


def director_rates(model, theta, theta_dot, theta_ddot=None):
    """Dd(theta) (3 x 2), d' = Dd theta' and, with theta'', d'' = Dd theta'' + D^2d[theta', theta']."""
    t = ufl.variable(theta)
    d = director_from_angles(model.theta_ref + t, model.frame)
    Dd = ufl.diff(d, t)
    d_dot = ufl.dot(Dd, theta_dot)
    if theta_ddot is None:
        return Dd, d_dot, None
    D2d = ufl.diff(Dd, t)
    i, j, k = ufl.indices(3)
    centripetal = ufl.as_vector(D2d[i, j, k] * theta_dot[j] * theta_dot[k], i)
    return Dd, d_dot, ufl.dot(Dd, theta_ddot) + centripetal


class DeploymentModel:
    """The released tape: root held at the stowed hub angle, contact kept, inertia added.

    ``tape`` is a :class:`TapeOnHub` in the stowed state (a coiling run's, or read from a
    checkpoint of either phase); its shell, contact and root attachment are reused.
    ``config`` (default: the tape's) sets the deployment; ``rho_inf`` overrides its spectral
    radius.
    """

    # lift-off: a centre-line point whose inner face is more than this many thicknesses off its
    # obstacle (the turn beneath or the hub) has left the coil (see lift_off)
    lift_off_gap = 2.0

    def __init__(self, tape: TapeOnHub, config: Config | None = None, rho_inf: float | None = None):
        self.tape = c = tape
        self.config = cfg = config or tape.config
        self.comm = c.comm
        self.model = model = c.model
        self.contact = c.contact
        self.hub_angle = c.root.angle
        c.root.set(1.0, self.hub_angle)
        c.contact.turn(self.hub_angle)
        self.bcs = c.root.bcs
        tp = cfg.tape
        self.rho_inf = cfg.deployment.rho_inf if rho_inf is None else rho_inf
        self.integrator = ti = GeneralizedAlpha(model.q, self.rho_inf)

        rho, h = tp.density, tp.h
        self.translational = rho * h  # kg/m^2
        self.rotary = rho * h**3 / 12  # kg
        self.energy = model.strain_energy + c.contact.energy

        # the hold on the free end (the guide and the pull of the coiling run), let go over
        # release_time (phases.release)
        self.hold = EndHold(c, ti, cfg.deployment.release_time)
        hold = self.hold.form

        self.scheme = "conserving" if self.rho_inf == 1.0 else "alpha"
        if self.scheme == "alpha":
            F, J, kinetic = self._alpha_forms(hold)
            options = {"pc_type": "cholesky"}
        else:
            F, J, kinetic = self._conserving_forms(hold)
            options = {}
        self.solver = SNESSolver.from_config(
            F,
            J,
            model.q,
            self.bcs,
            cfg.solver,
            prefix="deploy_",
            defaults=options,
            options=cfg.deployment.petsc_options,
            state_scale=model.rounding_scale(),
        )
        self.kinetic_form = dolfinx.fem.form(kinetic * model.jacobian * model.dx)
        self._internal_form = ufl.derivative(self.energy, model.q, model.dq)
        self.solver.point_forces.append(self.hold.point_force())
        # the turns' contact force at the level of the other internal forces: generalized-alpha's
        # average, and for rho_inf = 1 the trapezoidal mean of the two states (not a discrete
        # gradient: the penalty of the turns is the one force of the conserving scheme that is
        # only conserving to the order of the step)
        alpha_f = ti.parameters.alpha_f if self.scheme == "alpha" else 0.5
        self.solver.terms += c.contact_terms(model.q, self.bcs, 1.0 - alpha_f, (alpha_f, ti.q_old))
        self._tip_forms = [dolfinx.fem.form(model.phi[i] / tp.b * model.ds(FREE_END)) for i in range(3)]

    def _alpha_forms(self, hold):
        """Residual, Jacobian and kinetic energy density of generalized-alpha (rho_inf < 1).

        The equation of motion at the generalized-alpha levels, internal forces averaged between
        the two states (:meth:`GeneralizedAlpha.force_average`).
        """
        model, ti = self.model, self.integrator
        dA = model.jacobian
        du, dtheta = split_state(model.dq)
        a_u, a_theta = split_state(ti.a_m)
        _, v_theta = split_state(ti.v_f)
        _, theta_f = split_state(ti.q_f)
        Dd_f, _, d_ddot = director_rates(model, theta_f, v_theta, a_theta)
        translational = self.translational * ufl.dot(a_u, du) * dA * model.dx
        rotary = self.rotary * ufl.dot(d_ddot, ufl.dot(Dd_f, dtheta)) * dA * model.dx
        internal = ufl.derivative(self.energy, model.q, model.dq)
        F = translational + rotary + ti.force_average(internal) + hold

        # The Jacobian is exact but for the rotary inertia, linearised as its mass term alone
        # (rho h^3/12 Dd^T Dd (1 - alpha_m)/(beta dt^2)): its other parts (the turning of Dd,
        # the centripetal term) are not symmetric and 10^-8 of the translational mass. The
        # rest is symmetric (force averaging, penalty contact, the hold's spring), so MUMPS
        # factorises with LDL^T; the residual, and with it the solution, is exact.
        trial = ufl.TrialFunction(model.W)
        p = ti.parameters
        _, dtheta_trial = split_state(trial)
        rotary_mass = (1 - p.alpha_m) / (p.beta * ti.dt**2) * self.rotary
        rotary_mass = (
            rotary_mass * ufl.dot(ufl.dot(Dd_f, dtheta_trial), ufl.dot(Dd_f, dtheta)) * dA * model.dx
        )
        J = ufl.derivative(F - rotary, model.q, trial) + rotary_mass

        # kinetic energy of the current state (velocity: the integrator's latest)
        v_u, v_theta = split_state(ti.v_old)
        _, d_dot, _ = director_rates(model, model.theta, v_theta)
        kinetic = 0.5 * (self.translational * ufl.dot(v_u, v_u) + self.rotary * ufl.dot(d_dot, d_dot))
        return F, J, kinetic

    def _conserving_forms(self, hold):
        """Residual, Jacobian and kinetic energy density of the energy-conserving trapezoidal rule.

        rho_inf = 1: the trapezoidal (average acceleration) Newmark rule, with every force that
        derives from an energy written as its discrete gradient between the two states (the
        shell's and the contact's energy_secant_form), and the rotary inertia written for the
        director velocity, kept at the quadrature points: d'_{n+1} = 2 (d_{n+1} - d_n)/dt - d'_n
        and rho h^3/12 (d'_{n+1} - d'_n)/dt . dd, with dd the director's discrete variation.
        Tested with the step itself, every term is an exact difference (kinetic energies
        included), so strain + contact + kinetic energy changes only by the work of the hold:
        the scheme neither dissipates nor creates energy (Simo and Tarnow 1992; Gonzalez 1996),
        which the plain trapezoidal rule does not guarantee for nonlinear shells.
        """
        import basix.ufl

        model, ti, mesh = self.model, self.integrator, self.model.mesh
        element = basix.ufl.quadrature_element(mesh.basix_cell(), value_shape=(3,), degree=model.q_full)
        space = dolfinx.fem.functionspace(mesh, element)
        self.director_rate = dolfinx.fem.Function(space, name="director_rate")
        _, _, _, d_old = model.kinematics(ti.q_old)
        dd = model.director_variation(ti.q_old)
        rate = 2 * (model.d - d_old) / ti.dt - self.director_rate
        self._new_director_rate = dolfinx.fem.Expression(rate, compat.interpolation_points(space))
        du, _ = split_state(model.dq)
        a_u, _ = split_state(ti.a_m)
        inertia = self.translational * ufl.dot(a_u, du) + self.rotary * ufl.dot(
            (rate - self.director_rate) / ti.dt, dd
        )
        internal = sum(model.energy_secant_forms(ti.q_old)) + self.contact.energy_secant_form(ti.q_old, dd)
        F = inertia * model.jacobian * model.dx + internal + hold
        J = ufl.derivative(F, model.q, ufl.TrialFunction(model.W))
        v_u, _ = split_state(ti.v_old)
        kinetic = 0.5 * (
            self.translational * ufl.dot(v_u, v_u)
            + self.rotary * ufl.dot(self.director_rate, self.director_rate)
        )
        return F, J, kinetic

    def restore(self, path: str | Path) -> None:
        """Velocity, acceleration, the stowed state and the director velocity from a checkpoint
        written by :func:`write_deployment_checkpoint` (the state itself is already in place)."""
        ti, W = self.integrator, self.model.W
        parts = {}
        for prefix in ("velocity_", "acceleration_", "stowed_"):
            parts.update(checkpoint.empty_state_parts(W, prefix))
        extra = {"director_rate": self.director_rate} if self.scheme == "conserving" else {}
        checkpoint.read_functions(path, {**parts, **extra})
        checkpoint.set_state(ti.v_old, parts, "velocity_")
        checkpoint.set_state(ti.a_old, parts, "acceleration_")
        checkpoint.set_state(self.hold.stowed, parts, "stowed_")
        # the hold's dead forces are what held the end in the stowed state
        self.hold.restore_stowed()
        ti.restart()

    def advance(self) -> None:
        """After a converged step: the new state, velocities and accelerations become the old."""
        if self.scheme == "conserving":  # before q_old moves on
            self.director_rate.interpolate(self._new_director_rate)
        self.integrator.advance()

    # -- start ----------------------------------------------------------------------------------
    def initial_acceleration(self) -> None:
        """Translational a_0 from M a_0 = f_hold - f_int(q_0), at rest.

        At t = 0 the hold still balances the internal forces, so a_0 is the solver's residual
        noise; it is computed rather than assumed. The mass matrix at rest (no centripetal term)
        is solved with a direct solver; the attached root has zero acceleration.
        """
        model, ti = self.model, self.integrator
        trial, test = ufl.TrialFunction(model.W), model.dq
        a_u, a_theta = split_state(trial)
        du, dtheta = split_state(test)
        Dd, _, _ = director_rates(model, model.theta, ufl.as_vector([0.0, 0.0]))
        mass = (
            (
                self.translational * ufl.dot(a_u, du)
                + self.rotary * ufl.dot(ufl.dot(Dd, a_theta), ufl.dot(Dd, dtheta))
            )
            * model.jacobian
            * model.dx
        )
        M = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(mass), bcs=self.bcs)
        M.assemble()
        internal = dolfinx.fem.Function(model.W)
        dolfinx.fem.petsc.assemble_vector(internal.x.petsc_vec, dolfinx.fem.form(self._internal_form))
        internal.x.petsc_vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self.tape.add_self_contact_force(internal)
        b = internal.x.petsc_vec.copy()
        b.scale(-1.0)
        b.array[self.hold.end_dofs] += self.hold.dead_full
        fixed = np.concatenate([bc.dof_indices()[0] for bc in self.bcs])
        owned = b.getLocalSize()
        b.array[fixed[fixed < owned]] = 0.0
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
        ti.v_old.x.array[:] = 0.0
        ti.restart()
        for obj in (ksp, M, b, x):
            obj.destroy()

    # -- measures -------------------------------------------------------------------------------
    def energies(self) -> dict[str, float]:
        out = self.tape.energies()
        out["kinetic"] = global_scalar(self.kinetic_form, self.model.mesh.comm)
        return out

    def tip(self) -> np.ndarray:
        """Mean position of the free end [m] (3,)."""
        return np.array([global_scalar(f, self.model.mesh.comm) for f in self._tip_forms])

    def lift_off(self) -> dict[str, float]:
        """The coiled length and the deployed fraction lambda (:func:`measures.deployment.lift_off`)."""
        return lift_off(self.tape, self.lift_off_gap)

    def update(self) -> None:
        """After a converged step: winding angles from the new state (the hub stays put)."""
        self.contact.update(self.hub_angle)
        self.tape.accept_state()


def write_deployment_checkpoint(model: DeploymentModel, path: str | Path, meta: dict) -> None:
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
        functions["director_rate"] = model.director_rate
    model.tape.write_checkpoint(path, meta, functions)


def read_deployment_checkpoint(path: str | Path, config: Config, comm=MPI.COMM_WORLD):
    """A :class:`DeploymentModel` in the state of :func:`write_deployment_checkpoint`, and the meta."""
    tape, meta = TapeOnHub.read_checkpoint(path, config, comm)
    model = DeploymentModel(tape, config)
    model.restore(path)
    return model, meta
