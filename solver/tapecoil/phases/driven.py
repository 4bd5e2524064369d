"""A tape on its hub taken through time by loads the caller drives: the hub turned, bodies moved,
an end held or pulled.

A quasi-static load path stops where the tape snaps between equilibria that no path joins: a
fold forming as the tape is wound over a seed cylinder, a fold collapsing as the seed is
withdrawn (docs/notes/regimes.md). Explicit codes pass such snaps in time (Wilson et al. 2020 use
LS-DYNA). :class:`DrivenMotion` does it implicitly: the coiling model's potential (strain, hub and
turns' contact, the further bodies, the dead pull at the free end) with the shell's inertia
(:class:`~tapecoil.phases.deployment_forms.DeploymentForms`), stepped by generalized-alpha with a
spectral radius below 1 so that what the snaps excite at the mesh's scale is damped. The steps are
those of the load stepping (:class:`~tapecoil.core.stepping.Continuation`), time being the load:
a failed solve is retried shorter, and a run that cannot go on stops with the last converged state.
"""

from __future__ import annotations

from collections.abc import Callable

import ufl

from tapecoil.core import jit
from tapecoil.core.dofs import global_scalar
from tapecoil.core.newton import SNESSolver
from tapecoil.core.stepping import Continuation, StepRecord
from tapecoil.core.timeint import GeneralizedAlpha
from tapecoil.phases.coiling import CoilingProblem
from tapecoil.phases.deployment_forms import DeploymentForms


class DrivenMotion:
    """The tape of a :class:`CoilingProblem` moving in time under its loads and the caller's drive.

    ``bcs``: boundary conditions besides the model's (the root and the guide), e.g. an end held
    by its displacement (:class:`~tapecoil.phases.wrapping.EndDisplacement`). ``rho_inf``: the
    generalized-alpha spectral radius at infinite frequency. The motion starts at rest from the
    model's current state.
    """

    def __init__(self, model: CoilingProblem, bcs: tuple = (), rho_inf: float = 0.3, prefix: str = "driven_"):
        if not 0.0 <= rho_inf < 1.0:
            raise ValueError(f"rho_inf = {rho_inf!r}: a driven motion damps its snaps, 0 <= rho_inf < 1")
        self.model = model
        shell, tape = model.model, model.tape
        self.integrator = ti = GeneralizedAlpha(shell.q, rho_inf)
        forms = DeploymentForms(shell, ti, tape.contact, model.config.tape, energy=model.energy)
        F, J, kinetic = forms.alpha(-ufl.derivative(model.pull_work, shell.q, shell.dq))
        self.bcs = model.bcs + list(bcs)
        self.solver = SNESSolver.from_config(
            F,
            J,
            shell.q,
            self.bcs,
            model.config.solver,
            prefix=prefix,
            defaults={"pc_type": "cholesky", **tape.solver_options()},
            state_scale=shell.rounding_scale(),
        )
        alpha_f = ti.parameters.alpha_f
        self.solver.terms += tape.contact_terms(shell.q, self.bcs, 1.0 - alpha_f, (alpha_f, ti.q_old))
        self._kinetic = jit.form(kinetic * shell.jacobian * shell.dx)
        ti.v_old.x.array[:] = 0.0
        ti.a_old.x.array[:] = 0.0
        ti.restart()
        self.time = 0.0
        self.steps = 0
        self.iterations = 0

    def kinetic_energy(self) -> float:
        """The tape's kinetic energy at the last converged time [J] (collective)."""
        return global_scalar(self._kinetic, self.model.comm)

    def run(
        self,
        duration: float,
        drive: Callable[[float], None],
        dt: float,
        on_step: Callable[[StepRecord], None] | None = None,
        min_dt: float | None = None,
    ) -> None:
        """Step ``duration`` [s] on from the present time, ``drive(t)`` setting the loads at each
        new time t (hub angle, bodies, end displacement), in steps of at most ``dt`` [s] (at least
        ``min_dt``, default dt / 1000). ``on_step(record)`` after each converged step. Raises
        :class:`~tapecoil.core.stepping.ContinuationError` with the last converged state when a
        step cannot be made."""
        m, ti, start = self.model, self.integrator, self.time
        control = m.config.solver.control(
            initial_step=dt / duration, max_step=dt / duration, min_step=(min_dt or dt / 1000) / duration
        )

        def set_time(t: float) -> None:
            ti.set_step(t - self.time)
            drive(t)

        def converged(step: StepRecord) -> None:
            ti.advance()
            self.time, self.steps, self.iterations = (
                step.load,
                self.steps + 1,
                self.iterations + step.iterations,
            )
            m.contact.update(m.root.angle)
            m.tape.accept_state()
            if on_step is not None:
                on_step(step)

        cont = Continuation(
            self.solver.solve,
            set_time,
            m.model.q,
            control,
            predict=lambda t_from, t_to: ti.predict(t_to - t_from),
            refusal=m.tape.penetration_refusal,
        )
        cont.on_step = converged
        cont.run(start, start + duration)

    def destroy(self) -> None:
        self.solver.destroy()
