"""The released tape's equation of motion, discrete in time: the shell's inertia and the two schemes.

Inertia is the shell's consistent one. With the director d(theta), the kinetic energy per unit
reference area is rho h |u'|^2 / 2 + rho h^3 / 24 |d'|^2; its Euler-Lagrange term in the
direction (du, dtheta) is rho h u''.du + rho h^3/12 d''.(Dd dtheta), with
d'' = Dd theta'' + D^2d[theta', theta'] (the centripetal part of the rotary inertia). Both are
written with UFL's automatic differentiation of d(theta). :class:`DeploymentForms` states it for
generalized-alpha (rho_inf < 1) and for the energy-conserving trapezoidal rule (rho_inf = 1), and
the mass at rest the initial acceleration is solved with.
"""

from __future__ import annotations

import dolfinx
import ufl

from tapecoil.config import TapeConfig
from tapecoil.core import compat
from tapecoil.core.expression import expression_at
from tapecoil.core.timeint import GeneralizedAlpha
from tapecoil.models.shell import director_from_angles
from tapecoil.phases.release import split_state


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


class DeploymentForms:
    """The equation of motion of the shell ``model`` with its ``contact``, stepped by ``integrator``.

    ``energy`` is the potential (strain and contact, unless the caller gives another, with the
    energy of further bodies) and ``internal`` its derivative, the internal forces; ``friction``
    the hub friction's virtual work (UFL, of the state at the step's end; None: none), which
    the caller puts among a scheme's loads and which the reaction and the start at rest hold;
    ``translational`` and ``rotary`` the inertia per unit reference area of the ``tape``'s section.
    :meth:`alpha` and :meth:`conserving` give each scheme's residual,
    Jacobian and kinetic energy density, with the ``hold`` of the free end added to the residual.
    """

    def __init__(
        self, model, integrator: GeneralizedAlpha, contact, tape: TapeConfig, energy=None, friction=None
    ):
        self.model, self.integrator, self.contact = model, integrator, contact
        rho, h = tape.density, tape.h
        self.translational = rho * h  # kg/m^2
        self.rotary = rho * h**3 / 12  # kg
        self.energy = model.strain_energy + contact.energy if energy is None else energy
        self.internal = ufl.derivative(self.energy, model.q, model.dq)
        # every force of the tape's state: the internal ones and the hub's friction
        self.static = self.internal if friction is None else self.internal + friction
        # the conserving scheme's director velocity at the quadrature points (restart state)
        self.director_rate = None

    def alpha_forms(self, forces):
        """Residual and Jacobian of generalized-alpha: the inertia at the scheme's levels plus
        ``forces`` (a residual form of the shell's state: its averaged internal forces and
        whatever acts besides)."""
        model, ti = self.model, self.integrator
        dA = model.jacobian
        du, dtheta = split_state(model.dq)
        a_u, a_theta = split_state(ti.a_m)
        _, v_theta = split_state(ti.v_f)
        _, theta_f = split_state(ti.q_f)
        Dd_f, _, d_ddot = director_rates(model, theta_f, v_theta, a_theta)
        translational = self.translational * ufl.dot(a_u, du) * dA * model.dx
        rotary = self.rotary * ufl.dot(d_ddot, ufl.dot(Dd_f, dtheta)) * dA * model.dx
        F = translational + rotary + forces

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
        return F, ufl.derivative(F - rotary, model.q, trial) + rotary_mass

    def alpha(self, hold):
        """Residual, Jacobian and kinetic energy density of generalized-alpha (rho_inf < 1).

        The equation of motion at the generalized-alpha levels, internal forces averaged between
        the two states (:meth:`GeneralizedAlpha.force_average`).
        """
        model, ti = self.model, self.integrator
        F, J = self.alpha_forms(ti.force_average(self.internal) + hold)

        # kinetic energy of the current state (velocity: the integrator's latest)
        v_u, v_theta = split_state(ti.v_old)
        _, d_dot, _ = director_rates(model, model.theta, v_theta)
        kinetic = 0.5 * (self.translational * ufl.dot(v_u, v_u) + self.rotary * ufl.dot(d_dot, d_dot))
        return F, J, kinetic

    def conserving(self, hold):
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
        self._new_director_rate = expression_at(rate, compat.interpolation_points(space))
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

    def advance_director_rate(self) -> None:
        """The conserving scheme's director velocity of the converged step (before q_old moves on)."""
        self.director_rate.interpolate(self._new_director_rate)

    def weight(self, gravity):
        """The virtual work of gravity ``gravity`` (a (3,) UFL vector, a Constant so that every
        value, zero too, shares one compiled form) [m/s^2] on the tape, in the direction dq:
        rho h g . du per unit reference area (symmetric through the thickness: no director term)."""
        model = self.model
        du, _ = split_state(model.dq)
        return self.translational * ufl.dot(gravity, du) * model.jacobian * model.dx

    def weight_work(self, gravity):
        """Gravity's work over a step, from the integrator's previous state to the current one."""
        model = self.model
        u_old, _ = split_state(self.integrator.q_old)
        return self.translational * ufl.dot(gravity, model.u - u_old) * model.jacobian * model.dx

    def reaction(self):
        """The equation of motion at the converged state t_{n+1}, once the integrator has advanced
        (its velocity and acceleration are those of t_{n+1}): inertia plus internal forces, in the
        direction dq. On the root's dofs, what the attachment holds: the reaction."""
        return self.inertia_at_end() + self.static

    def inertia_at_end(self):
        """The inertia forces at t_{n+1} (the integrator advanced), in the direction dq."""
        model, ti = self.model, self.integrator
        du, dtheta = split_state(model.dq)
        a_u, a_theta = split_state(ti.a_old)
        _, v_theta = split_state(ti.v_old)
        Dd, _, d_ddot = director_rates(model, model.theta, v_theta, a_theta)
        inertia = self.translational * ufl.dot(a_u, du) + self.rotary * ufl.dot(d_ddot, ufl.dot(Dd, dtheta))
        return inertia * model.jacobian * model.dx

    def angular_momentum(self, frame):
        """The tape's angular momentum about the hub's axis (``frame``) per unit reference area,
        read from the velocities of t_{n+1} once the integrator has advanced:
        rho h (x - c) x v + rho h^3/12 d x d', along the axis."""
        model = self.model
        v_u, v_theta = split_state(self.integrator.v_old)
        _, d_dot, _ = director_rates(model, model.theta, v_theta)
        arm = model.phi - ufl.as_vector(frame.axis_point)
        spin = self.translational * ufl.cross(arm, v_u) + self.rotary * ufl.cross(model.d, d_dot)
        return ufl.dot(ufl.as_vector(frame.axis), spin)

    def mass_at_rest(self):
        """The mass form at rest (no centripetal term): translational and rotary inertia."""
        model = self.model
        trial, test = ufl.TrialFunction(model.W), model.dq
        a_u, a_theta = split_state(trial)
        du, dtheta = split_state(test)
        Dd, _, _ = director_rates(model, model.theta, ufl.as_vector([0.0, 0.0]))
        return (
            (
                self.translational * ufl.dot(a_u, du)
                + self.rotary * ufl.dot(ufl.dot(Dd, a_theta), ufl.dot(Dd, dtheta))
            )
            * model.jacobian
            * model.dx
        )
