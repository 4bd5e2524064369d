"""The hybrid's deployment with the hub free to turn: the hub's equation of motion solved with
the shell's and the beam's.

The tape's root is attached to the hub: the flattened beam's root node while the window starts
past the root, the window's root edge once it starts there. Its dofs are prescribed, g(zeta),
by the hub angle zeta (the hybrid's load parameter, :meth:`HybridProblem.set_load`). The hub
(:class:`~tapecoil.hub.rotor.HubRotor`) obeys, as with the full shell
(:mod:`tapecoil.phases.free_hub`),

    phi(zeta) = J a_m(zeta) + G(zeta) . F(q) = 0,

F the joint residual of shell and beam without the root's conditions (on the root's dofs, the
force the attachment supplies to the tape, at the generalized-alpha levels of the tape's own
equations; :meth:`CoupledSNESSolver.free_residuals`) and G = dg/dzeta the rate of the root's
prescribed dofs as the hub turns (central differences over ``angle_step``): G . F is the torque
the hub exerts on the tape. The spiral of turns is read from the winding angles, the
material's, and puts no torque on the hub.

Each trial angle is a joint solve of shell and beam with the root held at g(zeta). phi is
solved by Newton's method with its total derivative along the tape's equilibria, the full
shell's iteration (:class:`~tapecoil.phases.free_hub.HubNewton`): to first order a change of
angle moves the tape by w dzeta, with A w = [-(K G) on the free dofs, G on the root's], A the
joint Jacobian the last Newton iteration factorised (the root's rows the identity) and K G the
action of the Jacobian without conditions, here the central difference of the free residual
along G (two residuals, where the full shell assembles the action's form), and

    dphi/dzeta = J (1 - alpha_m) / (beta dt^2) + G' . F + (K G) . w,

(K G) . w standing for G . K w, which it is where K is symmetric; where it is not, only the
convergence slows: phi itself is exact.

The step dzeta = -phi / phi' carries the tape along by w dzeta, so the next joint solve starts
on its new equilibrium to first order and takes one or two iterations.
"""

from __future__ import annotations

import dolfinx.fem.petsc
import numpy as np

from tapecoil.core.dofs import owned_constrained_dofs, owned_size
from tapecoil.core.newton import SolveResult
from tapecoil.phases.free_hub import HubNewton

__all__ = ["HybridFreeHub"]


class HybridFreeHub(HubNewton):
    """The hub's equation and a :class:`~tapecoil.phases.hybrid_motion.HybridMotion`'s solved
    together (see the module): ``rotor`` the hub, ``moment_scale`` [N m] the size below which a
    torque is round-off (the section's bending moment at 1/R)."""

    # [rad]: the central difference of the free residual along G (the root moved by about
    # 1e-8 m: its truncation and rounding both far below the tangent's use, a predictor)
    action_step = 1e-6

    def __init__(self, motion, rotor, moment_scale: float):
        self.motion, self.rotor, self.moment_scale = motion, rotor, moment_scale
        self.hybrid, self.solver = motion.hybrid, motion.solver
        self.comm = self.hybrid.shell.comm
        spaces = [blk.q.function_space for blk in self.solver.blocks]
        self._held = [
            owned_constrained_dofs(V, blk.bcs) for V, blk in zip(spaces, self.solver.blocks, strict=True)
        ]
        self._sizes = [owned_size(V) for V in spaces]
        self.iterations = 0  # the hub's Newton steps over the run

    def place(self, angle: float) -> None:
        """The root (the beam's clamp or the window's attachment) at the hub angle ``angle``."""
        self.hybrid.set_load(angle)

    def _blocks(self, values: np.ndarray) -> list[np.ndarray]:
        """``values`` over the owned dofs of shell and beam, one after the other, split by block."""
        return np.split(values, [self._sizes[0]])

    def _prescribed(self, angle: float) -> np.ndarray:
        self.place(angle)
        out = []
        for blk, b in zip(self.solver.blocks, self.solver.b, strict=True):
            with b.localForm() as local:
                local.set(0.0)
            dolfinx.fem.petsc.set_bc(b, blk.bcs)
            out.append(b.array_r.copy())
        return np.concatenate(out)

    def _free_residual(self) -> np.ndarray:
        return np.concatenate(self.solver.free_residuals())

    def _dot(self, a: np.ndarray, b: np.ndarray) -> float:
        return self.comm.allreduce(float(a @ b))

    def torque(self, angle: float) -> float:
        """G . F [N m] at the present states, the root at ``angle`` (collective): the torque the
        hub exerts on the tape at the levels of the tape's equations."""
        rates, _ = self.root_rates(angle)
        return self._dot(rates, self._free_residual())

    def start(self) -> None:
        """At release, at rest: the hub's acceleration under the torque that the tape held it
        with (the coiling's), J a = -G . F (a massless hub is balanced by the tape alone)."""
        rotor = self.rotor
        if rotor.inertia > 0:
            rotor.acceleration = -self.torque(rotor.angle) / rotor.inertia

    def _move_states(self, change: np.ndarray) -> None:
        for blk, dq in zip(self.solver.blocks, self._blocks(change), strict=True):
            blk.q.x.array[: dq.size] += dq
            blk.q.x.scatter_forward()

    def _action(self, rates: np.ndarray) -> np.ndarray:
        """K G: the free residual's central difference along G (owned; collective)."""
        e = self.action_step
        self._move_states(e * rates)
        plus = self._free_residual()
        self._move_states(-2 * e * rates)
        minus = self._free_residual()
        self._move_states(e * rates)
        return (plus - minus) / (2 * e)

    def _response(self, rates: np.ndarray, action: np.ndarray) -> np.ndarray:
        """w: A w = [-(K G) free, G held], by the joint solver's factorisation (collective)."""
        solver = self.solver
        rhs, w = solver.r.duplicate(), solver.x.duplicate()
        parts = zip(solver.index_sets, self._blocks(rates), self._blocks(action), self._held, strict=True)
        for iset, g, kg, held in parts:
            sub = rhs.getSubVector(iset)
            sub.array[:] = -kg
            sub.array[held] = g[held]
            rhs.restoreSubVector(iset, sub)
        solver.snes.getKSP().solve(rhs, w)
        out = []
        for iset in solver.index_sets:
            sub = w.getSubVector(iset)
            out.append(sub.array_r.copy())
            w.restoreSubVector(iset, sub)
        rhs.destroy()
        w.destroy()
        return np.concatenate(out)

    # -- the hooks of HubNewton
    def tape_solve(self) -> SolveResult:
        return self.solver.solve()

    def balance(self, angle: float) -> tuple[float, float]:
        self._rates, self._curvatures = self.root_rates(angle)
        self._forces = self._free_residual()
        inertia, tape = self.rotor.inertia_torque(), self._dot(self._rates, self._forces)
        return inertia + tape, max(abs(inertia), abs(tape))

    def tangent(self) -> tuple[float, np.ndarray]:
        action = self._action(self._rates)
        w = self._response(self._rates, action)
        slope = (
            self.rotor.inertia_stiffness() + self._dot(self._curvatures, self._forces) + self._dot(action, w)
        )
        return slope, w

    def carry(self, change: float, response: np.ndarray) -> None:
        self._move_states(change * response)
