"""The deployment with the hub free to turn: the hub's equation of motion solved with the tape's.

The tape's root is attached to the hub (:class:`~tapecoil.hub.attachment.HubRoot`): its dofs are
prescribed, g(zeta), by the hub angle zeta. The hub (:class:`~tapecoil.hub.rotor.HubRotor`)
obeys

    phi(zeta) = J a_m(zeta) + G(zeta) . F(q) = 0,

where F is the tape's residual without the root's conditions (on the root's dofs, the force the
attachment supplies to the tape: G . F is the torque the hub must exert, the opposite of the
tape's torque on it) and G = dg/dzeta the rate of the root's dofs as the hub turns. It is the
virtual work of the tape and the hub together in a turn of the hub, at the generalized-alpha
levels of the tape's own equation.

Each trial angle is a tape solve (the solver's Newton, root held at g(zeta)); phi is then
solved by Newton's method with its total derivative along the tape's equilibria. To first order
a change of angle moves the tape by w dzeta, with A w = [-(K G) on the free dofs, G on the
root's], A the solver's factorised Jacobian (the root's rows the identity) and K G the action of
the Jacobian without conditions; K is symmetric, so G^T K = (K G)^T and

    dphi/dzeta = J (1 - alpha_m) / (beta dt^2) + G' . F + (K G) . w.

With the turns' real contact (``contact.turns = "surface"``) the hub carries a fairing behind
the root, which turns with it: the penalty energy E against the hub then depends on zeta at a
fixed tape, and dE/dzeta, the torque the tape puts on the fairing, joins phi (d2E/dzeta2 its
derivative; its cross-derivative with q is left out, which only slows the convergence: phi
itself is exact). The spiral obstacle is read from the winding angles, the material's, and
adds no such torque (:attr:`CoilContact.turns_with_hub`).

The step dzeta = -phi / phi' carries the tape along by w dzeta, so the next tape solve starts
on its new equilibrium to first order and takes one or two iterations. The root's rates G and
G' and the fairing's dE/dzeta are central differences over ``angle_step``.
"""

from __future__ import annotations

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from tapecoil.core import compat, jit
from tapecoil.core.dofs import global_dot, owned_constrained_dofs
from tapecoil.core.newton import SolveResult
from tapecoil.hub.rotor import HubRotor


def section_moment(config) -> float:
    """The tape section's bending moment at the curvature 1/R [N m], D11 b / R: the size of the
    torques a free hub's equation balances, below a fraction of which a torque is round-off."""
    tp = config.tape
    return config.wall.bending.D11 * tp.b / tp.R


class HubNewton:
    """Newton's method on a free hub's angle around the tape's solve (see the module): each
    trial angle is a tape solve with the root held there, then the hub's equation phi; the
    step -phi / phi' carries the tape along by its first-order response. A coupling supplies
    ``rotor`` and ``moment_scale`` [N m] (a torque below ``floor`` times it is round-off), and
    :meth:`place`, :meth:`_prescribed`, :meth:`tape_solve`, :meth:`balance`, :meth:`tangent`
    and :meth:`carry`."""

    angle_step = 1e-4  # [rad]: the central differences of the root's prescribed dofs
    max_iterations = 10
    # phi converged: this fraction of the torques in balance, or of the tape's section moment
    rtol, floor = 1e-7, 1e-9
    angle_round_off = 1e-14  # [-]: a change of angle below this relative size changes nothing

    def place(self, angle: float) -> None:
        """The root (and what turns with the hub) at the hub angle ``angle`` [rad]."""
        raise NotImplementedError

    def _prescribed(self, angle: float) -> np.ndarray:
        """The root placed at ``angle`` [rad], the values its conditions prescribe on the owned
        dofs (zero elsewhere)."""
        raise NotImplementedError

    def root_rates(self, angle: float) -> tuple[np.ndarray, np.ndarray]:
        """G and G' at ``angle`` on the owned dofs (zero off the root), central differences over
        ``angle_step``; the root left at ``angle``."""
        e = self.angle_step
        plus, minus, here = self._prescribed(angle + e), self._prescribed(angle - e), self._prescribed(angle)
        return (plus - minus) / (2 * e), (plus - 2 * here + minus) / e**2

    def tape_solve(self) -> SolveResult:
        """The tape's solve with the root where it is placed."""
        raise NotImplementedError

    def balance(self, angle: float) -> tuple[float, float]:
        """phi at the solved state and ``angle``, and the size of the torques it balances [N m]."""
        raise NotImplementedError

    def tangent(self) -> tuple[float, object]:
        """dphi/dzeta along the tape's equilibria and the tape's response w, after
        :meth:`balance` at the same state."""
        raise NotImplementedError

    def carry(self, change: float, response) -> None:
        """Move the tape by ``change`` times its response."""
        raise NotImplementedError

    def solve(self) -> SolveResult:
        """The step's tape and hub solved together from the predicted state and angle."""
        rotor = self.rotor
        total, result = 0, None
        for _ in range(self.max_iterations):
            self.place(rotor.new_angle)
            result = self.tape_solve()
            total += result.iterations
            if not result.converged:
                return SolveResult(False, total, result.reason, result.residual_norm)
            phi, size = self.balance(rotor.new_angle)
            if abs(phi) <= max(self.rtol * size, self.floor * self.moment_scale):
                return SolveResult(True, total, result.reason, result.residual_norm)
            slope, response = self.tangent()
            if not (np.isfinite(slope) and slope > 0):
                break
            change = -phi / slope
            if abs(change) <= self.angle_round_off * max(1.0, abs(rotor.new_angle)):
                # a hub far heavier than the tape: phi's tolerance is finer than the angle's
                # round-off times the hub's stiffness J (1 - alpha_m) / (beta dt^2)
                return SolveResult(True, total, result.reason, result.residual_norm)
            self.iterations += 1
            rotor.new_angle += change
            self.carry(change, response)
        reason = int(PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT)
        return SolveResult(False, total, reason, result.residual_norm if result is not None else np.inf)


class FreeHubCoupling(HubNewton):
    """The hub's and the tape's equations of a :class:`~tapecoil.phases.deployment.DeploymentProblem`
    solved together (see the module docstring); ``jacobian`` is the UFL Jacobian of the tape's
    solver."""

    def __init__(self, model, rotor: HubRotor, jacobian):
        self.m, self.rotor = model, rotor
        W = model.model.W
        self.root, self.contact, self.solver = model.tape.root, model.contact, model.solver
        self.rates = dolfinx.fem.Function(W)  # G, the action's argument (ghosts updated)
        self._action = jit.form(ufl.action(jacobian, self.rates))
        self._vec = compat.create_vector(W)
        self._w = compat.create_vector(W)
        self._held = owned_constrained_dofs(W, model.bcs)
        self._n = self._vec.getLocalSize()
        self.moment_scale = section_moment(model.config)
        self.iterations = 0  # hub Newton steps over the run (on every rank)

    def place(self, angle: float) -> None:
        """Root and spiral obstacle at the hub angle ``angle`` [rad]."""
        self.root.set(1.0, angle)
        self.contact.turn(angle)

    def _prescribed(self, angle: float) -> np.ndarray:
        self.root.set(1.0, angle)
        with self._vec.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.set_bc(self._vec, self.m.bcs)
        return self._vec.array.copy()

    def _assemble(self, form) -> PETSc.Vec:
        with self._vec.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(self._vec, form)
        self._vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return self._vec

    def obstacle_torque(self, angle: float) -> tuple[float, float]:
        """dE/dzeta and d2E/dzeta2 of the hub's contact energy at the state in place: the torque
        [N m] the tape puts on the fairing that turns with the hub, and its stiffness
        [N m/rad]; none without a fairing. The obstacle is left at ``angle``."""
        if not self.contact.turns_with_hub:
            return 0.0, 0.0
        e, energy = self.angle_step, []
        for a in (angle + e, angle - e, angle):
            self.contact.turn(a)
            energy.append(self.m.tape.hub_contact_energy())
        plus, minus, here = energy
        return (plus - minus) / (2 * e), (plus - 2 * here + minus) / e**2

    def residual(self, rates: np.ndarray, angle: float) -> tuple[float, float]:
        """phi at the current state and ``angle``, and the size of the torques it balances [N m]."""
        b = self._assemble(self.solver.F_form)
        for term in self.solver.terms:
            term.add_residual(b)
        W = self.m.model.W
        self._force = b.array.copy()
        torque = global_dot(W, rates, self._force)
        obstacle, self._obstacle_stiffness = self.obstacle_torque(angle)
        inertia = self.rotor.inertia_torque()
        return inertia + torque + obstacle, max(abs(inertia), abs(torque), abs(obstacle))

    def slope(self, rates: np.ndarray, curvature: np.ndarray) -> tuple[float, np.ndarray]:
        """dphi/dzeta along the equilibria and the tape's first-order response w (owned dofs),
        after :meth:`residual` at the same state."""
        W = self.m.model.W
        self.rates.x.array[: self._n] = rates
        self.rates.x.scatter_forward()
        action = self._assemble(self._action).array.copy()
        rhs = self._vec
        rhs.array[:] = -action
        rhs.array[self._held] = rates[self._held]
        self.solver.snes.getKSP().solve(rhs, self._w)
        w = self._w.array.copy()
        value = (
            self.rotor.inertia_stiffness()
            + self._obstacle_stiffness
            + global_dot(W, curvature, self._force)
            + global_dot(W, action, w)
        )
        return value, w

    # -- the hooks of HubNewton
    def tape_solve(self) -> SolveResult:
        return self.solver.solve()

    def balance(self, angle: float) -> tuple[float, float]:
        self._rates = self.root_rates(angle)
        return self.residual(self._rates[0], angle)

    def tangent(self) -> tuple[float, np.ndarray]:
        return self.slope(*self._rates)

    def carry(self, change: float, response: np.ndarray) -> None:
        q = self.m.model.q
        q.x.array[: self._n] += change * response
        q.x.scatter_forward()
