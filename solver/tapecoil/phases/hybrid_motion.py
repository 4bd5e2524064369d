"""The shell-beam hybrid in time: a :class:`~tapecoil.models.hybrid_problem.HybridProblem`'s
shell and beam stepped together by generalized-alpha in one Newton solve.

The shell's equation of motion is the deployment's (:mod:`tapecoil.phases.deployment_forms`: its
consistent inertia at the scheme's levels, its internal forces averaged between the step's
ends), the beam's is :mod:`tapecoil.models.beam_dynamics`'s, and the ties join them as in a
static solve, their penalty taken at the step's end (a constraint, as the supports are). Both
schemes share rho_inf and the step. After a converged step each scheme moves on and the hybrid
commits (the ties' frames, the beam's rotations), and the beam's scheme starts its next step
from a zero rotation.
"""

from __future__ import annotations

import dolfinx
import numpy as np

from tapecoil.config import SolverConfig, TapeConfig
from tapecoil.core import jit
from tapecoil.core.dofs import global_scalar
from tapecoil.core.timeint import GeneralizedAlpha
from tapecoil.models.beam_dynamics import BeamDynamics
from tapecoil.models.nodes import Nodes
from tapecoil.phases.deployment_forms import DeploymentForms

__all__ = ["HybridMotion"]


class HybridMotion:
    """``hybrid``'s shell and beam in time (see the module), from the state they are in, at
    rest. ``tape``: the shell's wall (its density and thickness give the inertia per unit area);
    ``line_density`` [kg/m] and ``rotary_inertia`` (J1, J2, J3) [kg m] the beam's. The loads
    are those of the hybrid's load parameter as it stands (:meth:`set_load` changes it), and
    those ``loads(scheme)`` gives for the shell's scheme: a residual form of the shell's state
    taken as it is (a hold's, at the scheme's level) and point forces on the shell's dofs, and
    the weight of shell and beam under ``gravity`` (3,) [m/s^2] (``shell_weight``: the shell's
    virtual work form of it, zero without gravity).
    :meth:`step` takes one step; the parts are at rest unless :meth:`set_rates` starts them
    moving. ``shell_forms``: the shell's inertia (a
    :class:`~tapecoil.phases.deployment_forms.DeploymentForms`), ``beam``: the beam's
    :class:`~tapecoil.models.beam_dynamics.BeamDynamics`."""

    def __init__(
        self,
        hybrid,
        tape: TapeConfig,
        line_density: float,
        rotary_inertia,
        rho_inf: float = 0.9,
        settings: SolverConfig | None = None,
        options: dict | None = None,
        loads=None,
        gravity=(0.0, 0.0, 0.0),
    ):
        self.hybrid = hybrid
        shell = hybrid.shell
        self.shell_scheme = GeneralizedAlpha(shell.model.q, rho_inf)
        # the shell's inertia (its internal forces are the shell problem's residual, averaged)
        self.shell_forms = inertia = DeploymentForms(
            shell.model, self.shell_scheme, None, tape, energy=shell.model.strain_energy
        )
        F_static, _ = shell.forms()
        forces = self.shell_scheme.force_average(F_static)
        # the weight of shell and beam (a ground test; zero in orbit), a Constant whatever its
        # value, so that runs with and without gravity share their compiled forms
        self.gravity = np.asarray(gravity, dtype=float)
        g = dolfinx.fem.Constant(shell.model.mesh, self.gravity)
        self.shell_weight = inertia.weight(g)
        forces = forces - self.shell_weight
        work = [inertia.weight_work(g)]
        point_forces = []
        if loads is not None:
            form, point_forces = loads(self.shell_scheme)
            forces = forces + form
        F_s, J_s = inertia.alpha_forms(forces)
        self.beam = BeamDynamics(hybrid.beam, line_density, rotary_inertia, rho_inf=rho_inf, gravity=gravity)
        work.append(self.beam.weight_work)
        self._weight_work = [jit.form(w) for w in work]
        self.settings = settings or SolverConfig()
        shell.point_forces.extend(point_forces)
        # the parts' contact force at the level of the other internal forces, as the full shell's
        alpha_f = self.shell_scheme.parameters.alpha_f
        old_states = [self.shell_scheme.q_old, self.beam.scheme.q_old]
        self.solver = hybrid._solver(
            F_s,
            J_s,
            self.settings,
            options,
            beam_forms=self.beam.forms,
            contact_levels=(1.0 - alpha_f, (alpha_f, old_states)),
        )
        self.time = 0.0

    @property
    def schemes(self) -> tuple:
        """The shell's and the beam's :class:`~tapecoil.core.timeint.GeneralizedAlpha`."""
        return self.shell_scheme, self.beam.scheme

    def rates(self) -> tuple:
        """Copies of (shell v, shell a, beam v, beam a) of the last converged time (dof arrays;
        the beam's are its nodes' (u', w) and (u'', w'))."""
        return tuple(f.x.array.copy() for s in self.schemes for f in (s.v_old, s.a_old))

    def set_rates(self, rates) -> None:
        """Start from the rates ``rates`` (as :meth:`rates` gives them) at the present state."""
        for scheme, (v, a) in zip(self.schemes, (rates[:2], rates[2:]), strict=True):
            scheme.v_old.x.array[:] = v
            scheme.a_old.x.array[:] = a
        self.restart_rates()

    def rate_fields(self) -> dict:
        """The velocities and accelerations of the last converged time, as cell fields (views,
        :mod:`tapecoil.core.cell_state`): a restart's."""
        from tapecoil.core.cell_state import function_field

        return {
            f"{part}_{kind}": function_field(getattr(scheme, f"{kind}_old"))
            for part, scheme in zip(("shell", "beam"), self.schemes, strict=True)
            for kind in ("v", "a")
        }

    def restart_rates(self) -> None:
        """Step on from the present state with the rates set in the schemes (:meth:`set_rates`,
        or through :meth:`rate_fields`)."""
        for scheme in self.schemes:
            scheme.restart()
        self.beam.committed()

    def set_load(self, value: float) -> None:
        """The hybrid's load parameter (its loads per unit load) from now on."""
        self.hybrid.set_load(value)
        self.hybrid.beam.committed_load = value

    def step(self, dt: float):
        """One step of ``dt`` [s]; the states stay where they were unless it converged."""
        schemes = (self.shell_scheme, self.beam.scheme)
        states = [s.q.x.array.copy() for s in schemes]
        for scheme in schemes:
            scheme.set_step(dt)
            scheme.predict(dt)
        result = self.solver.solve()
        if not result.converged:
            for scheme, state in zip(schemes, states, strict=True):
                scheme.q.x.array[:] = state
                scheme.q.x.scatter_forward()
            return result
        self.commit_step()
        self.time += dt
        return result

    def weight_work(self) -> float:
        """Gravity's work on shell and beam over the step just solved [J] (before the schemes
        move on; collective)."""
        if not np.any(self.gravity):
            return 0.0
        comm = self.hybrid.shell.comm
        return sum(global_scalar(form, comm) for form in self._weight_work)

    def start_falling(self) -> None:
        """At rest under the release's hold, which balances the internal forces, with gravity: the
        acceleration g on every free translation of shell and beam, the held ones at rest (the
        consistent start but for the consistent mass's coupling across the root's element)."""
        parts = (
            (self.shell_scheme, Nodes(self.hybrid.shell.model).u_dofs, self.hybrid.shell.bcs),
            (self.beam.scheme, self.hybrid.beam.model.node_u_dofs, self.hybrid.beam.bcs),
        )
        for scheme, u_dofs, bcs in parts:
            a = scheme.a_old.x.array
            a[:] = 0.0
            a[u_dofs] = self.gravity
            for bc in bcs:
                a[bc.dof_indices()[0]] = 0.0
            scheme.a_old.x.scatter_forward()

    def commit_step(self) -> None:
        """After a converged step: each scheme moves on, then the hybrid commits (the ties'
        frames, the beam's rotations, the winding angles) and the beam's scheme starts its next
        step from a zero rotation."""
        for scheme in self.schemes:
            scheme.advance()
        self.hybrid.commit()
        self.beam.committed()

    def destroy(self) -> None:
        self.solver.destroy()
