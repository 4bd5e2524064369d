"""The release of a stowed tape's free end: the hold of the coiling let go over a short time.

During coiling the guide and the pull hold the free end. At release both are replaced by a
hold that is let go smoothly: a stiff spring to the stowed end plus the dead forces that held it
there, both scaled by a factor that falls from 1 to 0 over ``release_time`` (:meth:`hold_at`).
"""

from __future__ import annotations

from dataclasses import dataclass

import dolfinx
import numpy as np
import ufl

from tapecoil.core import jit
from tapecoil.core.dofs import assemble_into, global_dot
from tapecoil.core.newton import PointForce
from tapecoil.core.smoothing import smoothstep
from tapecoil.geometry.meshes import FREE_END


@dataclass
class _Magnitude:
    """A mutable ``value`` (an array here) for :class:`PointForce`."""

    value: np.ndarray


def split_state(expr):
    """(u, theta) parts of a state-shaped expression of the mixed space (3 + 2 components)."""
    return ufl.as_vector([expr[i] for i in range(3)]), ufl.as_vector([expr[3], expr[4]])


class EndHold:
    """The hold on the free end of ``tape`` (a TapeOnHub), released over ``release_time`` [s].

    ``form`` is the spring's virtual work, applied at the level q_f of the ``integrator`` (its
    work over a step is taken there too); :meth:`point_force` the dead forces, for the solver.
    """

    def __init__(self, tape, integrator, release_time: float):
        model = tape.model
        self.model, self.integrator, self.comm = model, integrator, tape.comm
        self.release_time = release_time
        self.factor = dolfinx.fem.Constant(model.mesh, 1.0)
        self.stowed = dolfinx.fem.Function(model.W, name="stowed_state")
        self.stowed.x.array[:] = model.q.x.array
        u0, theta0 = split_state(self.stowed)
        u, theta = split_state(model.q)
        du, dtheta = split_state(model.dq)
        ell = tape.element_length
        k_hold = (
            tape.config.wall.axial_modulus * tape.config.tape.h / ell
        )  # per unit edge length: an element's membrane stiffness
        spring = k_hold * (ufl.dot(u - u0, du) + ell**2 * ufl.dot(theta - theta0, dtheta))
        self.form = integrator.at_midpoint(self.factor * spring * model.ds(FREE_END))
        self._compiled = jit.form(self.form)
        subs = [(0, j) for j in range(3)] + [(1, j) for j in range(2)]
        self.end_dofs = np.unique(np.concatenate([tape.edge_dofs(FREE_END, s) for s in subs]))
        self.dead = _Magnitude(np.zeros(len(self.end_dofs)))
        self._internal = jit.form(ufl.derivative(tape.energy, model.q, model.dq))
        self.dead_full = self.end_internal_force()

    def point_force(self) -> PointForce:
        """The dead forces on the end's owned dofs, scaled with the hold (for the solver)."""
        return PointForce(self.end_dofs, self.dead)

    def end_internal_force(self) -> np.ndarray:
        """f_int(q) on the free end's owned dofs: in the stowed state, what the pull and guide held."""
        return assemble_into(dolfinx.fem.Function(self.model.W), self._internal)[self.end_dofs].copy()

    def restore_stowed(self) -> None:
        """The dead forces of the stowed state, after ``stowed`` was read back (a restart)."""
        q = self.model.q
        current = q.x.array.copy()
        q.x.array[:] = self.stowed.x.array
        self.dead_full = self.end_internal_force()
        q.x.array[:] = current

    def hold_at(self, t: float) -> float:
        """The factor of the hold at time t: 1 at release, 0 after ``release_time`` (C1 smoothstep).

        An instantaneous release would hit the end's tiny mass with the guide's reactions
        (accelerations of 10^7 m/s^2 on the coarse mesh) and start a shock; dead forces alone,
        without the spring, leave the end's rotations unstable. The thesis's explicit run
        released with smooth-step amplitudes too.
        """
        if self.release_time <= 0:
            return 0.0
        return 1.0 - float(smoothstep(t / self.release_time))

    def release(self, t: float) -> None:
        """Set the hold (spring and dead forces) of time t."""
        factor = self.hold_at(t)
        self.factor.value = factor
        self.dead.value = factor * self.dead_full

    def work(self) -> float:
        """The hold's work on the tape over the step just solved [J] (collective; before advance).

        Its force at the level where the scheme applies it (state q_f, hold factor of that time:
        what the residual holds) dotted with the step.
        """
        force = -assemble_into(dolfinx.fem.Function(self.model.W), self._compiled)
        force[self.end_dofs] += self.dead.value
        dq = self.model.q.x.array - self.integrator.q_old.x.array
        return global_dot(self.model.W, force, dq)
