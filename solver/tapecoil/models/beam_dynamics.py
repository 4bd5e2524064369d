"""A geometrically exact beam in time: its inertia and generalized-alpha steps.

The beam's rotations are updated (:mod:`tapecoil.models.beam`): within a step the unknown theta
is the spatial rotation vector of the step, Lambda = exp(theta^) Lambda_n, and it is zero at the
step's start. The time scheme (:class:`~tapecoil.core.timeint.GeneralizedAlpha`) runs on the
state q = (u, theta) as it stands, so that for the rotations its previous state is zero and its
velocity and acceleration are the spatial angular velocity w and acceleration at the step's
start (Simo and Vu-Quoc 1988 in their spatial form, the rates carried from step to step in
spatial components; the rate of the step's rotation vector is w to first order in theta).

The kinetic energy per unit length is (1/2) rho_A |u'|^2 + (1/2) w . I w, I = Lambda J Lambda^T,
J = diag(J1, J2, J3) the section's mass moments of inertia per unit length about its axes (the
line's tangent and the section's axes 2 and 3). Its Euler-Lagrange terms in the direction
(du, dtheta) are rho_A u''.du + (I w' + w x I w).dw, dw = T(theta) dtheta the spatial virtual
rotation of a variation of the rotation vector (T the left Jacobian of SO(3):
I + f2 Theta + f3 Theta^2, f2 = (1 - cos a)/a^2, f3 = (a - sin a)/a^3), so that inertia and
the energy's derivative in theta work on the same variation. The inertia is taken at the
scheme's intermediate levels (u'' at a_m, w at v_f, Lambda at the level theta_f) and the
internal force is averaged between the step's ends, as the shell's deployment does
(:mod:`tapecoil.core.timeint`).
"""

from __future__ import annotations

import dolfinx
import numpy as np
import ufl

from tapecoil.core import jit
from tapecoil.core.newton import SNESSolver
from tapecoil.core.timeint import GeneralizedAlpha
from tapecoil.models.beam import SERIES_BELOW, _rodrigues_coefficients, _skew, rotation

__all__ = ["BeamDynamics", "left_jacobian"]


def left_jacobian(theta):
    """T(theta) = I + f2 Theta + f3 Theta^2 (UFL), the spatial spin of a variation of the rotation
    vector theta: d exp(theta^) = (T dtheta)^ exp(theta^); regular at theta = 0 (f2 is
    Rodrigues' coefficient of the beam's rotation, f3 = (a - sin a)/a^3)."""
    a2 = ufl.dot(theta, theta)
    _, f2 = _rodrigues_coefficients(a2)
    small = ufl.lt(a2, SERIES_BELOW)
    safe = ufl.conditional(small, 1.0, a2)
    a = ufl.sqrt(safe)
    f3 = ufl.conditional(
        small, 1 / 6 - a2 / 120 + a2**2 / 5040 - a2**3 / 362880, (a - ufl.sin(a)) / (a * safe)
    )
    T = _skew(theta)
    return ufl.Identity(3) + f2 * T + f3 * T * T


class BeamDynamics:
    """A :class:`~tapecoil.models.beam_problem.BeamProblem` taken through time: its supports,
    its loads at the problem's committed load parameter and the energies beside the beam's, with
    the beam's inertia (see the module).

    ``line_density``: rho_A [kg/m]; ``rotary_inertia``: J1, J2, J3 [kg m], the section's mass
    moments of inertia per unit length about the tangent and its axes 2 and 3. ``rho_inf``: the
    scheme's high-frequency spectral radius (1: the trapezoidal rule); ``gravity`` (3,) [m/s^2]:
    the beam's weight rho_A g per unit length, from the start. :meth:`step` takes one time
    step of the beam alone; ``forms`` are its residual and Jacobian for a joint solve
    (:mod:`tapecoil.phases.hybrid_motion`); :meth:`kinetic_energy` and :meth:`momenta` read the
    motion from the velocities; ``reaction_form`` is the equation of motion at the last converged
    time (its residual on held dofs: what holds them).
    """

    def __init__(
        self,
        problem,
        line_density: float,
        rotary_inertia,
        rho_inf: float = 0.9,
        rtol: float = 1e-9,
        gravity=(0.0, 0.0, 0.0),
    ):
        if not line_density > 0:
            raise ValueError(f"a beam's line density must be positive, got {line_density!r} kg/m")
        J = np.asarray(rotary_inertia, dtype=float)
        if J.shape != (3,) or not np.all(J > 0):
            raise ValueError(
                f"a beam's rotary inertia needs three positive moments [kg m], got {rotary_inertia!r}"
            )
        self.problem = problem
        model = problem.model
        self.model, self.line_density, self.rotary_inertia = model, float(line_density), J
        self.scheme = scheme = GeneralizedAlpha(model.q, rho_inf)
        p = scheme.parameters
        du, dtheta = ufl.split(model.dq)
        a_m, v_f = scheme.a_m, scheme.v_f
        acceleration = ufl.as_vector([a_m[i] for i in range(3)])
        spin_rate = ufl.as_vector([a_m[i] for i in range(3, 6)])
        spin = ufl.as_vector([v_f[i] for i in range(3, 6)])
        theta_f = (1 - p.alpha_f) * model.theta  # the previous theta is zero: a step's start
        section_inertia = ufl.diag(ufl.as_vector([float(j) for j in J]))
        frame = rotation(theta_f) * model.frame_n
        inertia = frame * section_inertia * frame.T
        moment = inertia * spin_rate + ufl.cross(spin, inertia * spin)
        self.inertia_form = (
            self.line_density * ufl.dot(acceleration, du)
            + ufl.dot(moment, left_jacobian(model.theta) * dtheta)
        ) * model.dx
        residual, _ = problem.forms()
        F = self.inertia_form + scheme.force_average(residual)
        # the weight (constant: not averaged) and its work over a step, gravity a Constant
        # whatever its value (zero too), so that runs with and without it share compiled forms
        g = dolfinx.fem.Constant(model.mesh, np.asarray(gravity, dtype=float))
        self.weight = self.line_density * ufl.dot(g, du) * model.dx
        u_old = ufl.as_vector([scheme.q_old[i] for i in range(3)])
        self.weight_work = self.line_density * ufl.dot(g, ufl.split(model.q)[0] - u_old) * model.dx
        F = F - self.weight
        self.forms = (F, ufl.derivative(F, model.q, ufl.TrialFunction(model.W)))
        self.rtol = rtol
        self.solver = None  # the beam's own, for steps of the beam alone
        self.time = 0.0
        V = model.W
        self._velocity = dolfinx.fem.Function(V)
        u, theta = ufl.split(self._velocity)
        frame_now = model.frame_n  # at a step's start, the current frame
        inertia_now = frame_now * section_inertia * frame_now.T
        self._kinetic = jit.form(
            (0.5 * self.line_density * ufl.dot(u, u) + 0.5 * ufl.dot(theta, inertia_now * theta)) * model.dx
        )
        # the equation of motion at t_{n+1}, once the scheme has advanced and the beam committed
        # (theta zero, T(0) = I: the rotation's residual is the spatial moment itself)
        a_u, a_w = (ufl.as_vector([scheme.a_old[i] for i in range(k, k + 3)]) for k in (0, 3))
        w = ufl.as_vector([scheme.v_old[i] for i in range(3, 6)])
        end_moment = inertia_now * a_w + ufl.cross(w, inertia_now * w)
        self.reaction_form = (
            self.line_density * ufl.dot(a_u, du) + ufl.dot(end_moment, dtheta)
        ) * model.dx + residual
        self.reaction_form = self.reaction_form - self.weight
        x = ufl.SpatialCoordinate(model.mesh) + ufl.split(model.q)[0]
        self._momenta = [jit.form(self.line_density * u[i] * model.dx) for i in range(3)] + [
            jit.form((self.line_density * ufl.cross(x, u)[i] + (inertia_now * theta)[i]) * model.dx)
            for i in range(3)
        ]

    def set_velocity(self, velocity) -> None:
        """Start from the velocity field ``velocity(x)`` -> (6, n): (u', w) at points x (3, n) [m]
        (the state at rest before it); the acceleration starts at zero."""
        v = self.scheme.v_old
        for i in range(2):
            v.sub(i).interpolate(lambda x, i=i: np.asarray(velocity(x))[3 * i : 3 * i + 3])
        v.x.scatter_forward()
        self.scheme.a_old.x.array[:] = 0.0

    def step(self, dt: float):
        """One time step of ``dt`` [s]; returns the solve's result (its state kept only when it
        converged: then the beam's rotations are committed and the rates moved on)."""
        scheme, model = self.scheme, self.model
        if self.solver is None:
            self.solver = SNESSolver(
                *self.forms,
                model.q,
                self.problem.bcs,
                prefix=f"{self.problem.name}_dynamics_",
                options={"pc_factor_mat_solver_type": "mumps", "pc_type": "lu"},
                rtol=self.rtol,
                atol=1e-12,
                state_scale=model.rounding_scale(),
            )
            self.solver.point_forces = self.problem.point_forces
        scheme.set_step(dt)
        start = model.q.x.array.copy()
        scheme.predict(dt)
        result = self.solver.solve()
        if not result.converged:
            model.q.x.array[:] = start
            model.q.x.scatter_forward()
            return result
        scheme.advance()
        model.commit()  # theta back to zero: the next step's start
        self.committed()
        self.time += dt
        return result

    def committed(self) -> None:
        """After the scheme has advanced and the beam committed its rotations: the scheme's
        previous rotation (the next step's start) is zero."""
        self.scheme.q_old.x.array[self.model._theta_dofs] = 0.0

    def kinetic_energy(self) -> float:
        """(1/2) rho_A |u'|^2 + (1/2) w.I w over the beam [J], from the velocities (collective)."""
        from tapecoil.core.dofs import global_scalar

        self._velocity.x.array[:] = self.scheme.v_old.x.array
        return global_scalar(self._kinetic, self.model.mesh.comm)

    def momenta(self) -> np.ndarray:
        """The linear momentum [kg m/s] and the angular momentum about the origin [kg m^2/s]
        (x rho_A u' + I w, x the current place), from the velocities (collective)."""
        from tapecoil.core.dofs import global_scalar

        self._velocity.x.array[:] = self.scheme.v_old.x.array
        return np.array([global_scalar(f, self.model.mesh.comm) for f in self._momenta])
