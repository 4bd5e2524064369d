"""A deployment's time stepping, whichever model it steps.

The release's legs, the step limits that ``[deployment]`` and ``[solver]`` set, and one
:class:`~tapecoil.core.stepping.Continuation` per leg in time: a model hands over a
:class:`TimeStepper` (its state, its solve, how it takes a step's length, its predictor, its
local error, the refusal of a state and what it does once a step is accepted), the loop steps it
and calls ``on_step`` after every converged step. ``on_step`` ends the run by raising
:class:`Deployed`, or has the loop go on from the converged state with the stepper the model
gives now by raising :class:`StepOn` (the hybrid, whose window has moved, is another model from
there). A step that fails even cut back raises :class:`~tapecoil.core.stepping.ContinuationError`,
the state the last converged one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tapecoil.core.stepping import Continuation
from tapecoil.phases.stepped import EASY_ITERATIONS


class Deployed(Exception):
    """Raised from ``on_step``: the run has reached its end (``deployment.lambda_end``)."""


class StepOn(Exception):
    """Raised from ``on_step``: leave the leg's continuation and step on from the converged state
    with the stepper the model gives now."""


@dataclass
class TimeStepper:
    """What the time loop needs of a model in motion.

    ``state``: what the continuation saves and restores (a Function, or a joint state);
    ``solve()``: the step's nonlinear solve; ``set_step(dt, target)``: the step's length [s]
    into the time scheme(s) and the loads at the time ``target`` [s]; ``predict(dt)``: the
    initial guess for a step of ``dt``; ``error()``: the step's local error over its tolerance;
    ``refusal()``: why a converged state is not accepted (None: accepted); ``commit()``: once a
    step is accepted, before its state is saved (:class:`~tapecoil.core.stepping.Continuation`).
    """

    state: object
    solve: Callable
    set_step: Callable[[float, float], None]
    predict: Callable[[float], None]
    error: Callable[[], float] | None = None
    refusal: Callable[[], str | None] | None = None
    commit: Callable[[], None] | None = None


# a converged step may end with more energy than it started with by no more than this share of
# the stowed energy. The scheme dissipates, but a step's energy also moves with the penalty
# contact's and the ties' stiff springs by a part in a thousand or so; a step that makes a
# hundredth of all the tape holds, half of what a whole run may dissipate, is no motion of the
# tape: its Newton solve has converged to a spurious root
ENERGY_GROWTH = 1e-2


def energy_refusal(before: float, after: float, work: float, stowed: float) -> str | None:
    """Why a converged step is not accepted for the energy it made, None if it is: ``before``
    and ``after`` the tape's energy (strain, contact, kinetic) at the step's start and end [J],
    ``work`` the loads' work on it over the step [J], ``stowed`` the energy at release [J]."""
    growth = after - before - work
    if growth > ENERGY_GROWTH * stowed:
        return (
            f"the step made energy, {growth / stowed:.3g} of the stowed energy (a spurious "
            "root of the step's equations)"
        )
    return None


def time_legs(release_time: float, t_end: float, dt: float, max_dt: float) -> list[tuple[float, float]]:
    """A deployment's legs of time stepping, each (its end [s], its largest step [s]): the
    release, when there is one, then the rest up to ``t_end``."""
    # the release in steps of at most a twentieth of it: the hold's spring is stiff and its work is
    # integrated over the steps; then the steps grow to max_dt
    release = min(release_time, t_end)
    legs = [(release, min(release / 20, dt))] if release > 0 else []
    legs.append((t_end, max(max_dt, dt)))
    return legs


def smallest_time_step(t_end: float, dt: float) -> float:
    """A deployment's smallest time step [s] before it gives up ([solver] min_step = 0), absolute
    whatever the span left, so that a restart steps as the first run."""
    # a millionth of the run, but at most a thousandth of the first step: far below any step a
    # converging deployment takes, so reaching it means the cut-backs have failed
    return min(1e-6 * t_end, 1e-3 * dt)


def step_error(parts, tolerance: float, h: float, comm) -> float:
    """A step's local error in the displacement over its tolerance (collective; before the
    step's state becomes the old one); at most 1 is accurate enough.

    ``parts``: (scheme, owned translational dofs) of each time scheme stepped (the full shell's
    one, the hybrid's shell and beam), each scheme's local error e
    (:meth:`~tapecoil.core.timeint.GeneralizedAlpha.local_error`). Their root mean square over
    the nodes against ``tolerance`` times the step's own displacement, or times the thickness
    ``h`` [m] while the tape barely moves (at release). The director angles and the beam's
    rotations are left out: they follow the displacement's gradient.
    """
    sums = np.zeros(3)
    for scheme, dofs in parts:
        error = scheme.local_error()[dofs]
        increment = scheme.q.x.array[dofs] - scheme.q_old.x.array[dofs]
        sums += [error @ error, increment @ increment, dofs.size]
    sums = comm.allreduce(sums)
    count = max(sums[2], 1.0)
    rms_error, rms_increment = np.sqrt(sums[0] / count), np.sqrt(sums[1] / count)
    return float(rms_error / (tolerance * (rms_increment + h)))


def step_in_time(config, legs, clock, stepper: Callable[[], TimeStepper], on_step) -> None:
    """Step from ``clock.time`` through the ``legs`` (:func:`time_legs`) with the stepper that
    ``stepper()`` gives, calling ``on_step(step, end)`` after each converged step (``step`` a
    :class:`~tapecoil.core.stepping.StepRecord`, ``end`` its leg's end [s]), which moves
    ``clock.time`` and ``clock.next_step`` on (the step the continuation tries next; a restart
    passes it, and a leg's first continuation takes it). ``config``: the run's configuration.
    Returns at the last leg's end; :class:`Deployed` and
    :class:`~tapecoil.core.stepping.ContinuationError` propagate."""
    d = config.deployment
    smallest = smallest_time_step(d.t_end, d.dt)
    for end, max_dt in legs:
        while clock.time < end * (1 - 1e-12):
            current = stepper()
            span = end - clock.time
            control = config.solver.control(
                initial_step=min(d.dt / span, 1.0),
                max_step=min(max_dt / span, 1.0),
                min_step=smallest / span,
                range_fraction=d.t_end / span,  # [solver] min_step: a fraction of t_end
            )
            continuation = Continuation(
                current.solve,
                lambda target, current=current: current.set_step(target - clock.time, target),
                current.state,
                control,
                predict=lambda t_from, t_to, current=current: current.predict(t_to - t_from),
                error=current.error if d.error_tolerance > 0 else None,
                refusal=current.refusal,
                commit=current.commit,
                easy_iterations=EASY_ITERATIONS,
            )
            continuation.on_step = lambda step, end=end: on_step(step, end)
            first, clock.next_step = clock.next_step, None
            try:
                continuation.run(clock.time, end, first_step=first)
            except StepOn:
                continue
