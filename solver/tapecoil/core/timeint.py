"""Implicit time integration: generalized-alpha (Chung and Hulbert 1993) in UFL.

The unknown of a step is the new state q_{n+1}; acceleration and velocity follow from the
Newmark relations

    a_{n+1} = (q_{n+1} - q_n - dt v_n) / (beta dt^2) - (1 - 2 beta) / (2 beta) a_n
    v_{n+1} = v_n + dt ((1 - gamma) a_n + gamma a_{n+1})

and the equation of motion is imposed at the intermediate levels

    inertia(q_f, v_f, a_m) + (1 - alpha_f) f(q_{n+1}) + alpha_f f(q_n) = 0,
    q_f = (1 - alpha_f) q_{n+1} + alpha_f q_n  (likewise v_f),
    a_m = (1 - alpha_m) a_{n+1} + alpha_m a_n.

The internal force f is averaged between the two configurations rather than evaluated at the
interpolated one, q_f (the "generalized midpoint"): a tape swinging round the hub turns by
0.05 to 0.1 rad per step, and the chord between two rotated configurations is shorter by
cos(dphi/2), a spurious membrane strain of dphi^2/8 that with E h = 13 MN/m put up to 2 J into
the membrane in single steps of a coarse deployment run (more than the whole stored energy).
Force averaging (Erlicher, Bonaventura and Bursi 2002) has no such strain and the same
linear properties.

The four parameters come from the high-frequency spectral radius rho_inf (fenicsx-notes.md):
alpha_m = (2 rho_inf - 1)/(rho_inf + 1), alpha_f = rho_inf/(rho_inf + 1),
gamma = 1/2 - alpha_m + alpha_f, beta = (1 - alpha_m + alpha_f)^2 / 4. rho_inf = 1 is the
trapezoidal Newmark rule (no numerical dissipation); smaller values damp the highest
frequencies (the shell's through-thickness shear and membrane modes, far above the deployment
motion) with second-order accuracy kept.

Residuals are built from forms written for the state q (:meth:`GeneralizedAlpha.force_average`),
so a model states its energy once. For rho_inf = 1 the deployment model replaces the averaged
forces by energy-consistent ones (discrete gradients, see :mod:`tapecoil.phases.deployment`): the
plain trapezoidal rule is not energy-stable for nonlinear shells.
"""

from __future__ import annotations

from dataclasses import dataclass

import dolfinx
import numpy as np
import ufl


@dataclass(frozen=True)
class AlphaParameters:
    """The generalized-alpha parameters for a spectral radius rho_inf in [0, 1]."""

    rho_inf: float
    alpha_m: float
    alpha_f: float
    gamma: float
    beta: float

    @classmethod
    def from_spectral_radius(cls, rho_inf: float) -> AlphaParameters:
        if not 0.0 <= rho_inf <= 1.0:
            raise ValueError(f"rho_inf must be in [0, 1], got {rho_inf}")
        alpha_m = (2 * rho_inf - 1) / (rho_inf + 1)
        alpha_f = rho_inf / (rho_inf + 1)
        gamma = 0.5 - alpha_m + alpha_f
        beta = 0.25 * (1 - alpha_m + alpha_f) ** 2
        return cls(rho_inf, alpha_m, alpha_f, gamma, beta)


def newmark_rates(p: AlphaParameters, dt: float, q, q0, v0, a0):
    """The new velocity and acceleration (v, a) of a step from (q0, v0, a0) to q over dt by the
    Newmark relations (floats or dof arrays)."""
    a = (q - q0 - dt * v0) / (p.beta * dt**2) - (1 - 2 * p.beta) / (2 * p.beta) * a0
    v = v0 + dt * ((1 - p.gamma) * a0 + p.gamma * a)
    return v, a


class GeneralizedAlpha:
    """Time-discrete kinematics of the state Function ``q`` (any function space).

    Holds the previous state, velocity and acceleration (Functions) and the step size (a
    Constant), and gives the UFL expressions of the new acceleration and velocity and of the
    intermediate levels, all in terms of the unknown ``q``.
    """

    def __init__(self, q: dolfinx.fem.Function, rho_inf: float):
        self.q = q
        self.parameters = p = AlphaParameters.from_spectral_radius(rho_inf)
        V = q.function_space
        self.q_old = dolfinx.fem.Function(V, name="previous_state")
        self.v_old = dolfinx.fem.Function(V, name="velocity")
        self.a_old = dolfinx.fem.Function(V, name="acceleration")
        self.q_old.x.array[:] = q.x.array
        self.dt = dolfinx.fem.Constant(V.mesh, 1.0)
        dt = self.dt
        self.a_new = (q - self.q_old - dt * self.v_old) / (p.beta * dt**2) - (1 - 2 * p.beta) / (
            2 * p.beta
        ) * self.a_old
        self.v_new = self.v_old + dt * ((1 - p.gamma) * self.a_old + p.gamma * self.a_new)
        self.q_f = (1 - p.alpha_f) * q + p.alpha_f * self.q_old
        self.v_f = (1 - p.alpha_f) * self.v_new + p.alpha_f * self.v_old
        self.a_m = (1 - p.alpha_m) * self.a_new + p.alpha_m * self.a_old

    def at_midpoint(self, form):
        """``form`` (written for the state q) with q replaced by the level q_f."""
        return ufl.replace(form, {self.q: self.q_f})

    def force_average(self, form):
        """(1 - alpha_f) ``form`` + alpha_f ``form`` at the previous state: the averaged force."""
        p = self.parameters
        return (1 - p.alpha_f) * form + p.alpha_f * ufl.replace(form, {self.q: self.q_old})

    # -- the step, on dof arrays ---------------------------------------------------------------
    def _new_rates(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        q, q0, v0, a0 = (f.x.array for f in (self.q, self.q_old, self.v_old, self.a_old))
        return newmark_rates(self.parameters, dt, q, q0, v0, a0)

    def new_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """The velocity and acceleration (dof arrays) the step in place ends with, as
        :meth:`advance` will take them (call before it)."""
        return self._new_rates(float(self.dt.value))

    def set_step(self, dt: float) -> None:
        self.dt.value = dt

    def predict(self, dt: float) -> None:
        """Initial guess for the step: constant velocity, q_n + dt v_n.

        Not the Taylor expansion with dt^2/2 a_n: the stiff modes' accelerations alternate in
        sign from step to step (they are being damped), and extrapolating them misleads Newton.
        On the coarse benchmark's deployment it takes markedly fewer steps and Newton
        iterations than the Taylor guess.
        """
        self.q.x.array[:] = self.q_old.x.array + dt * self.v_old.x.array

    def local_error(self) -> np.ndarray:
        """The step's local truncation error in q on the dof array (call before :meth:`advance`).

        Newmark's update of q matches a Taylor series but for dt^3 (1/6 - beta) times the third
        derivative; with that derivative as the acceleration's difference over the step,

            e = (beta - 1/6) dt^2 (a_{n+1} - a_n)

        (Zienkiewicz and Xie 1991; Hulbert and Jang 1995 for generalized-alpha, whose update of
        q is Newmark's). It costs nothing: both accelerations are at hand.
        """
        p = self.parameters
        _, a = self._new_rates(float(self.dt.value))
        return (p.beta - 1.0 / 6.0) * float(self.dt.value) ** 2 * (a - self.a_old.x.array)

    def advance(self) -> None:
        """After a converged step: the new state, velocity and acceleration become the old ones."""
        dt = float(self.dt.value)
        v, a = self._new_rates(dt)
        self.v_old.x.array[:] = v
        self.a_old.x.array[:] = a
        self.q_old.x.array[:] = self.q.x.array

    def restart(self) -> None:
        """Start afresh from the current state q (velocity and acceleration kept as they are)."""
        self.q_old.x.array[:] = self.q.x.array
