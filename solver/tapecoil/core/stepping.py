"""Adaptive load stepping with cut-back, and pseudo-transient relaxation through snaps.

The load parameter t runs from t_start to t_end. After an easy step (few Newton iterations)
the step grows; after a failed one the state returns to the last converged one and the step is
cut back. A step that still fails after ``max_cutbacks`` consecutive cut-backs, or at the
smallest allowed step, is retried with pseudo-transient relaxation when the caller provides
one. So is a failing step when the steps have been cut back ``max_cutbacks`` times since one
last converged without a cut-back: near a snap's turning point each step converges only at
half the length of the one before, and the loads would creep towards the turning point
without ever passing it. Relaxation: a viscous term c (q - q_prev) is added and a sequence
of pseudo-time solves at the fixed target load lets the state fall through the instability (a
snap) to the next stable branch, where a plain Newton solve finishes. If that fails too, the
step is cut back again and retried (Newton, then relaxation) while it is at least the
smallest allowed step: from nearer the snap's turning point the relaxation has less far to
fall. Below that the run stops with :class:`ContinuationError`; the state is then the last converged one.

With an ``error`` estimate (time stepping), a converged step is also judged on its accuracy:
``error()`` returns the step's estimated local error over what the caller tolerates (1 is the
tolerance). A step above 1 is rejected and retried shorter; an accepted one sets the next
step from the estimate, dt_next = dt min(grow, max(1/5, 0.9 error^(-1/2))): the exponent 1/2
is that of an error O(dt^3) measured against the step's increment O(dt) (a second-order
integrator). Growth also waits for an easy Newton solve, since a step that converges with
difficulty would, longer, not converge at all.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from tapecoil.config import StepControl
from tapecoil.core.dofs import global_norm


class ContinuationError(RuntimeError):
    """Load stepping could not proceed; ``load`` is the last converged load parameter."""

    def __init__(self, message: str, load: float):
        super().__init__(message)
        self.load = load


@dataclass
class StepRecord:
    """One converged load step; ``next_step`` is the step the continuation will try next.

    ``iterations`` and ``wall_time`` are those of the accepted attempt alone: its Newton
    iterations (for a step relaxed through a snap, those of the pseudo-time solves and the
    plain solve that finished it) and its wall time [s]. What the step cost in all is
    ``total_iterations`` and ``total_wall_time``: every attempt at it counted, the ones that
    failed and were cut back, refused or rejected as inaccurate included; ``attempts`` is how
    many there were (a relaxation through a snap counts as one).
    """

    load: float
    step: float
    iterations: int
    cutbacks: int
    relaxed: bool
    wall_time: float
    next_step: float = 0.0
    error: float | None = None  # the accuracy estimate over its tolerance (error-controlled steps)
    rejected: int = 0  # converged attempts rejected as inaccurate before this one
    attempts: int = 1
    total_iterations: int | None = None  # None: the accepted attempt's (a record of one attempt)
    total_wall_time: float | None = None

    def __post_init__(self):
        if self.total_iterations is None:
            self.total_iterations = self.iterations
        if self.total_wall_time is None:
            self.total_wall_time = self.wall_time


@dataclass
class Relaxation:
    """Pseudo-transient relaxation: a viscous coefficient and the previous state it refers to.

    ``coefficient`` and ``previous`` are the DOLFINx Constant and Function the residual form
    uses in a term coefficient * M(q - previous, dq); with the coefficient 0 that term is absent.
    ``scale`` is the coefficient's starting value; ``max_iterations`` bounds the pseudo-time solves.
    """

    coefficient: object
    previous: object
    scale: float
    max_iterations: int = 200
    tolerance: float = 1e-4  # relative change of the state below which plain Newton is tried
    # the Function the viscous term acts on and whose change is measured, when the solved
    # state is a joint one (a hybrid's shell); None: the continuation's state
    state: object = None


@dataclass
class Continuation:
    """Drives ``solve`` (returning an object with ``converged`` and ``iterations``) over the load."""

    solve: Callable[[], object]
    set_load: Callable[[float], None]
    # the dolfinx Function solved for, or an object with snapshot() and restore(saved) (the
    # states of a coupled solve, :class:`~tapecoil.core.coupled_newton.JointState`)
    state: object
    control: StepControl
    relaxation: Relaxation | None = None
    on_step: Callable[[StepRecord], None] | None = None
    # predict(t_from, t_to): an initial guess for the solve at t_to from the converged state at t_from
    predict: Callable[[float, float], None] | None = None
    # error(): the converged step's local error over its tolerance (None: steps by Newton alone)
    error: Callable[[], float] | None = None
    # refusal(): why a converged state is not accepted (None: accepted); such a step is cut
    # back as a failed solve is, and the message is the run's when no shorter step passes
    refusal: Callable[[], str | None] | None = None
    # commit(): called once a step is accepted, before its state is saved as the one to return
    # to: a model that keeps part of its state outside ``state`` (the reference frames of a
    # beam's incremental rotations) moves that part on and may rewrite ``state``
    commit: Callable[[], None] | None = None
    easy_iterations: int = 5
    history: list[StepRecord] = field(default_factory=list)
    # Newton iterations of every attempt of :meth:`run`, the failed ones and those of a step
    # that never converged (a run stopped by ContinuationError) included
    total_iterations: int = 0

    def _snapshot(self):
        """A copy of the state (a Function's local array, or what a joint state's ``snapshot`` gives)."""
        take = getattr(self.state, "snapshot", None)
        return take() if take is not None else self.state.x.array.copy()

    def _restore(self, saved) -> None:
        restore = getattr(self.state, "restore", None)
        if restore is not None:
            restore(saved)
        else:
            self.state.x.array[:] = saved

    def _relax(self, target: float) -> tuple[bool, int]:
        """Pseudo-transient solves at the fixed load ``target``; True when back at equilibrium.

        Each pseudo-time step solves the regularised problem; the viscosity falls by a factor 4
        after each success and rises by 4 after a failure. Once the state barely moves, a plain
        Newton solve is tried from it: a stable equilibrium is then close.
        """
        relax = self.relaxation
        viscous = relax.state if relax.state is not None else self.state
        q = viscous.x.array
        c = relax.scale
        total = 0
        self.set_load(target)
        try:
            for _ in range(relax.max_iterations):
                relax.previous.x.array[:] = q
                before = self._snapshot()
                relax.coefficient.value = c
                result = self.solve()
                total += result.iterations
                if not result.converged:
                    self._restore(before)
                    c *= 4.0
                    continue
                change = global_norm(viscous.function_space, q - relax.previous.x.array) / max(
                    global_norm(viscous.function_space, q), 1e-300
                )
                if change < relax.tolerance:
                    relax.coefficient.value = 0.0
                    relaxed_state = self._snapshot()
                    plain = self.solve()
                    total += plain.iterations
                    if plain.converged:
                        return True, total
                    self._restore(relaxed_state)
                c /= 4.0
        finally:
            relax.coefficient.value = 0.0
        return False, total

    def settle(self, load: float) -> tuple[bool, int]:
        """Pseudo-transient relaxation at the fixed ``load`` from the state in place (set off an
        unstable equilibrium) down to a stable one: the fall through a snap under a load held.
        Returns (converged, Newton iterations); on failure the state is the last relaxed one.
        Needs ``relaxation``."""
        if self.relaxation is None:
            raise ValueError("settle: the continuation has no relaxation")
        return self._relax(load)

    def _error_factor(self, error: float) -> float:
        """The factor on the step that brings ``error`` (over its tolerance) to 0.9, within [1/5, grow]."""
        if error <= 0.0:
            return self.control.grow
        return min(self.control.grow, max(0.2, 0.9 * error**-0.5))

    def run(
        self, t_start: float, t_end: float, stops: tuple[float, ...] = (), first_step: float | None = None
    ) -> list[StepRecord]:
        """Step the load from t_start to t_end, landing exactly on every value in ``stops``.

        ``first_step``: the step to try first (a restart passes the ``next_step`` of the last
        record before the stop, so that it steps on as the uninterrupted run would have);
        by default ``control.initial_step`` of the span.
        """
        ctl = self.control
        span = t_end - t_start
        marks = sorted(
            {s for s in stops if t_start < s < t_end} | {t_end}, key=lambda s: (s - t_start) / span
        )
        t = t_start
        dt = ctl.initial_step * span if first_step is None else first_step
        saved = self._snapshot()
        cutbacks = rejected = 0
        # every attempt at the step under way: how many, their Newton iterations, since when
        attempts = spent = 0
        started = None
        # cut-backs of the steps accepted since the last one that needed none
        limping = 0
        while marks:
            target = t + dt
            if (target - marks[0]) * math.copysign(1, span) >= -1e-12 * abs(span):
                target = marks[0]
            t0 = time.perf_counter()
            if started is None:
                started = t0
            self.set_load(target)
            if self.predict is not None:
                self.predict(t, target)
            result = self.solve()
            iterations, relaxed = result.iterations, False
            attempts += 1
            spent += iterations
            self.total_iterations += iterations
            refused = self.refusal() if (result.converged and self.refusal is not None) else None
            if not result.converged or refused is not None:
                self._restore(saved)
                cutbacks += 1
                dt *= ctl.cutback
                # creeping towards a snap, or towards a load no step reaches without refusal
                creeping = (self.relaxation is not None or refused is not None) and (
                    limping + cutbacks > ctl.max_cutbacks
                )
                if cutbacks <= ctl.max_cutbacks and abs(dt) >= ctl.min_step * abs(span) and not creeping:
                    continue
                if refused is not None or self.relaxation is None:
                    self.set_load(t)
                    what = f"{refused}, at load" if refused else "no convergence at load"
                    raise ContinuationError(
                        f"{what} {target:.6g} after {cutbacks - 1} cut-backs "
                        f"(step {abs(dt / ctl.cutback):.3g}); last converged load {t:.6g}",
                        t,
                    )
                ok, iterations = self._relax(target)
                attempts += 1
                spent += iterations
                self.total_iterations += iterations
                if not ok:
                    self._restore(saved)
                    self.set_load(t)
                    # a shorter step lands nearer the snap's turning point, from where the
                    # relaxation has less far to go: cut back again while the step allows
                    if abs(dt) >= ctl.min_step * abs(span):
                        continue
                    raise ContinuationError(
                        f"no convergence at load {target:.6g}, even with pseudo-transient relaxation "
                        f"(down to a step of {abs(dt / ctl.cutback):.3g}); last converged load {t:.6g}",
                        t,
                    )
                relaxed = True
            step = target - t
            error = None if (self.error is None or relaxed) else self.error()
            if error is not None and error > 1.0 and abs(step) > ctl.min_step * abs(span):
                self._restore(saved)
                rejected += 1
                dt = step * max(ctl.min_step * abs(span) / abs(step), self._error_factor(error))
                continue
            if target == marks[0]:
                marks.pop(0)
            t = target
            if self.commit is not None:
                self.commit()
            saved = self._snapshot()
            easy = iterations <= self.easy_iterations and cutbacks == 0
            if error is None:
                if easy:
                    dt *= ctl.grow
            elif abs(step) < abs(dt) * (1 - 1e-9):
                # shortened to land on a stop: its error says too little to grow the next step by
                dt *= min(self._error_factor(error), 1.0)
            else:
                dt = step * (self._error_factor(error) if easy else min(self._error_factor(error), 1.0))
            dt = math.copysign(min(abs(dt), ctl.max_step * abs(span)), span)
            if relaxed:  # restart gently after a snap
                dt = ctl.initial_step * span
            now = time.perf_counter()
            record = StepRecord(
                target,
                step,
                iterations,
                cutbacks,
                relaxed,
                now - t0,
                dt,
                error,
                rejected,
                attempts=attempts,
                total_iterations=spent,
                total_wall_time=now - started,
            )
            self.history.append(record)
            limping = 0 if (cutbacks == 0 or relaxed) else limping + cutbacks
            cutbacks = rejected = attempts = spent = 0
            started = None
            if self.on_step is not None:
                self.on_step(record)
        return self.history
