"""The coiling run: flatten, then turn the hub in adaptive steps, a history row per step.

:class:`CoilingRun` steps the loads of a :class:`~tapecoil.phases.coiling.CoilingProblem`
(flattening, then hub rotation with cut-back and relaxation through snaps) and records what each
converged step measured (:mod:`tapecoil.phases.coiling_rows`); :class:`CoilingPhase` is the run
as a phase of the one runner (:mod:`tapecoil.phases.runner`), and :func:`run_coiling` runs it
into a results directory.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.core.dofs import global_size
from tapecoil.core.stepping import Continuation, ContinuationError, Relaxation
from tapecoil.measures.coiling import coil_measures, coiled_cells, hub_torque_measure, ploy_measure
from tapecoil.models.solver_terms import relaxation_scale
from tapecoil.phases.coiling import CoilingProblem, check_free_end_room, read_checkpoint, write_checkpoint
from tapecoil.phases.coiling_rows import CoilingRows
from tapecoil.phases.model_tag import by_hybrid
from tapecoil.phases.runner import LOG, Phase, run_phase
from tapecoil.phases.stepped import EASY_ITERATIONS, SteppedRun


@dataclass
class CoilingResult:
    """The outcome of a coiling run: per-step history, final measures and run information."""

    history: list[dict] = field(default_factory=list)
    info: dict = field(default_factory=dict)
    completed: bool = False
    message: str = ""


class CoilingRun(SteppedRun):
    """Flatten then coil to the target hub angle, recording a history row per converged step.

    ``on_step(row)`` is called (on every rank) after each converged step, e.g. for output, with
    its row (:class:`~tapecoil.phases.coiling_rows.CoilingRows`).
    """

    easy_iterations = EASY_ITERATIONS
    # the largest step [rad] of each predictor, unless coiling.max_step sets one: the shift
    # predicts a turning hub's state well enough for long steps, fewer in all than shorter ones
    # take; the secant needs short ones (the benchmark's counts: docs/notes/coiling.md)
    max_steps: ClassVar[dict[str, float]] = {"shift": 1.0, "secant": 0.3}

    def __init__(self, model: CoilingProblem, on_step=None, max_step: float | None = None, stop=None):
        super().__init__(CoilingResult(), on_step, stop)
        self.m = model
        self.max_step = max_step or model.config.coiling.max_step or self.max_steps[model.predictor]
        self.rows = CoilingRows(model)
        self.next_step = None  # the step the load stepping tries next (for a restart)

    def restart_state(self) -> dict:
        """What, besides the model's state, the stepping needs to go on as if never stopped."""
        previous = self.m.predictions.previous_converged()
        return {
            "next_step": self.next_step,
            "last_potential": self.rows.last_potential,
            "previous_angle": None if previous is None else previous[0],
            **self._history_state(),
        }

    def restore(self, state: dict) -> None:
        """Continue from :meth:`restart_state` (the model restored from the same checkpoint)."""
        self.next_step = state["next_step"]
        self.rows.last_potential = state["last_potential"]
        self._restore_history(state)

    def continuation(self, set_load, control, predict=None) -> Continuation:
        """A load stepping of this run's solver: ``set_load(t)`` applies the load t; cut-backs and
        pseudo-transient relaxation through snaps as in the coiling (for another load, e.g. an
        end's displacement, on the same model)."""
        m = self.m
        relax = Relaxation(
            m.viscosity,
            m.previous,
            scale=relaxation_scale(m.config.wall.bending, m.element_length),
            max_iterations=100,
        )
        return Continuation(
            m.solver.solve,
            set_load,
            m.model.q,
            control,
            relaxation=relax,
            predict=predict,
            easy_iterations=self.easy_iterations,
        )

    def flatten(self) -> None:
        m = self.m
        steps = m.config.coiling.flatten_steps
        control = m.config.solver.control(initial_step=1.0 / steps, max_step=1.0 / steps, min_step=1e-6)
        cont = self.continuation(m.set_flattening, control)
        cont.on_step = lambda step: self._record(self.rows.row("flatten", step.load, step))
        cont.run(0.0, 1.0)

    def coil(
        self,
        final_angle: float,
        start_angle: float = 0.0,
        stops: tuple[float, ...] = (),
        first_step: float | None = None,
    ) -> None:
        """Turn the hub from ``start_angle`` to ``final_angle`` [rad], landing on ``stops``.

        ``first_step`` [rad]: the first step to try (a restart's ``next_step``). Step limits are
        absolute (radians), so a restarted run steps as the uninterrupted one would.
        """
        m = self.m
        # the step limits in radians, as fractions of the span the continuation works on (which
        # turns the hub back, paying the tape out, when final_angle < start_angle)
        span = abs(final_angle - start_angle)
        hub_angle = m.config.coiling.hub_angle
        control = m.config.solver.control(
            initial_step=min(min(0.05, self.max_step) / span, 1.0),
            max_step=min(self.max_step / span, 1.0),
            min_step=min(1e-6 * hub_angle, 1e-4) / span,
            range_fraction=hub_angle / span,  # [solver] min_step: a fraction of the hub angle
        )

        def converged(step):
            m.update(step.load)
            self.next_step = step.next_step
            self._record(self.rows.row("coil", step.load, step))
            self._check_stop(m.comm)

        m.update(start_angle)
        cont = self.continuation(m.set_hub_angle, control, predict=m.predict)
        cont.refusal = m.tape.penetration_refusal
        cont.on_step = converged
        cont.run(start_angle, final_angle, stops, first_step=first_step)

    def run(self) -> CoilingResult:
        """Flatten and coil to ``config.coiling.hub_angle``; a failure keeps the last converged state."""
        try:
            self.flatten()
            self.coil(self.m.config.coiling.hub_angle)
            self.result.completed = True
        except ContinuationError as err:
            self.result.message = str(err)
        return self.result


class HubTurningPhase(Phase):
    """A phase that turns the hub of a :class:`CoilingProblem` (the coiling, a driven hub's payout):
    it is where the hub is, its checkpoint is the coiling model's, and its run figures are the
    same."""

    unit = "rad"

    def __init__(self, model: CoilingProblem):
        super().__init__()
        self.model = model

    def position(self) -> float:
        return self.model.root.angle

    def checkpoint_meta(self) -> dict:
        return {"hub_angle": self.model.root.angle, "tension": float(self.model.tension.value)}

    def write_checkpoint(self, path: Path, meta: dict) -> None:
        write_checkpoint(self.model, path, meta)

    def coiling_summary(self, interrupted, t_start: float, measures: dict) -> dict:
        """A coiling's summary: its state, hub angles, ``measures`` and run figures (the steps
        of the hub's turning counted)."""
        return {
            "completed": self.completed,
            "message": self.message,
            "interrupted": None if interrupted is None else interrupted.name,
            "hub_angle": self.model.root.angle,
            "target_hub_angle": self.target,
            "measures": measures,
            "run": self.run_figures(len([r for r in self.history if r["phase"] == "coil"]), t_start),
        }

    def run_figures(self, steps: int, t_start: float) -> dict:
        """The summary's "run": ranks, DOFs, mesh, ``steps`` (the phase's own count), Newton
        iterations, penetration, wall times and the cost of an iteration."""
        model, history = self.model, self.history
        res, comm = model.strip.resolution, model.comm
        timing = model.solver.timing_per_iteration()
        return {
            "ranks": comm.size,
            "dofs": global_size(model.model.W),
            "mesh": f"{res.along} x {res.across}",
            "predictor": model.predictor,
            "penalty": model.penalty,
            "steps": steps,
            "newton_iterations": int(sum(r["newton_iterations"] for r in history)),
            # this process's, including the attempts that failed and were cut back
            "newton_iterations_total": int(model.solver.timings["iterations"]),
            "max_penetration": max((r["max_penetration"] for r in history), default=0.0),
            "wall_time": history[-1]["wall_time"] if history else 0.0,
            "process_wall_time": time.perf_counter() - t_start,
            "assembly_per_iteration": timing["assembly"],
            "linear_solve_per_iteration": timing["linear_solve"],
            # of which the turns' real contact's own (0 where it is a form: the spiral)
            "contact_per_iteration": timing["terms"],
        }


class CoilingPhase(HubTurningPhase):
    """Coiling as a phase of :func:`~tapecoil.phases.runner.run_phase`: flatten, then turn the hub
    to ``coiling.hub_angle``; the coil's measures at the end (:mod:`tapecoil.measures.coiling`)."""

    name, checkpoint_name = "coiling", "stowed"

    def __init__(self, model: CoilingProblem, restart: dict | None = None, stop=None):
        super().__init__(model)
        self.target = model.config.coiling.hub_angle
        self.run = CoilingRun(model, stop=stop)
        self.run.on_step = self._on_step
        self.history = self.run.result.history
        self.fresh = restart is None
        # the ploy region one turn in, where the free part is long (Sec. 7 of the physics brief)
        self.ploy = dict(restart.get("ploy") or {}) if restart else {}
        self._cells = None
        if restart is not None:
            self.run.restore(restart)
            self.history = self.run.result.history

    def restart_state(self) -> dict:
        return {**self.run.restart_state(), "ploy": self.ploy}

    def _on_step(self, row: dict) -> None:
        if row["phase"] == "coil" and abs(row["hub_angle"] - 2 * math.pi) < 1e-9:
            self.ploy.update(ploy_measure(self.model.tape))
        if self.on_row is not None:
            self.on_row(row)

    def progress(self, row: dict) -> tuple[float, float, int, str, bool]:
        coiling = row["phase"] == "coil"
        return row["hub_angle"], row["step"], row["newton_iterations"], f" {row['phase']}", coiling

    def advance(self) -> None:
        if self.fresh:
            self.run.flatten()
        self.run.coil(
            self.target,
            start_angle=self.model.root.angle,
            stops=(2 * math.pi,),
            first_step=self.run.next_step,
        )
        self.completed = True

    def finish(self, directory: Path) -> None:
        """coiled_cells.csv: the final state at the cell midpoints (for the pictures)."""
        self._cells = write_coiled_cells(self.model, directory)

    def summary(self, interrupted, t_start: float) -> dict:
        """The coiling phase's summary: measures against the theory and the run's figures."""
        measures = coil_measures(self.model.tape, self._cells)
        if self.ploy:
            measures["ploy_length_one_turn"] = self.ploy
        torque = hub_torque_measure(self.history)
        if torque is not None:
            measures["hub_torque"] = torque
        summary = self.coiling_summary(interrupted, t_start, measures)
        if self.run.rows.stability is not None:
            summary["stability"] = self.run.rows.stability.summary(self.history)
        return summary


def write_coiled_cells(model: CoilingProblem, directory: Path) -> dict:
    """coiled_cells.csv in ``directory``: the state at the cell midpoints (for the pictures);
    returns them (collective)."""
    cells = coiled_cells(model.tape)
    if model.comm.rank == 0:
        np.savetxt(
            directory / "coiled_cells.csv",
            np.column_stack(list(cells.values())),
            delimiter=",",
            header=",".join(cells),
            comments="",
        )
    return cells


def run_coiling(
    config: Config,
    directory: str | Path,
    comm=MPI.COMM_WORLD,
    resume: str | Path | None = None,
    progress: bool = True,
    stop=None,
) -> tuple[dict, CoilingProblem]:
    """Coil to the stowed state, writing into ``directory``; returns the phase summary and model.

    ``directory`` receives coiling_history.csv (a row per converged step), coiling.bp and
    snapshots/ (every ``output.vtx_every`` steps and the last state), coiled_cells.csv (the
    final state at the cell midpoints) and stowed/ (the checkpoint: the latest converged state,
    every ``output.checkpoint_every`` steps and at the end, completed or not). The caller writes
    the configuration and summary.json (:mod:`tapecoil.app.results`).
    ``resume``: a checkpoint directory to continue from (its hub angle, history and step size:
    the run goes on as if it had never stopped). ``stop``: :class:`~tapecoil.core.interrupt.StopSignals`;
    on a signal the run ends after the current step, writes everything and reports
    ``interrupted`` in the summary.
    """
    check_free_end_room(config)
    t_start = time.perf_counter()
    restart = None
    if resume is not None:
        model, meta = read_checkpoint(resume, config, comm)
        restart = meta.get("run")
        if restart is None:
            raise ValueError(f"{resume} holds no coiling restart state")
        if by_hybrid(restart):
            raise ValueError(f"{resume} is the hybrid model's coiling: resume it with model.kind = 'hybrid'")
    else:
        model = CoilingProblem(config, comm)
    phase = CoilingPhase(model, restart, stop)
    res = model.strip.resolution
    if restart is not None:
        LOG.info("coiling resumed from %s at %.6g rad", resume, model.root.angle)
        if meta["completed"] and model.root.angle >= phase.target:
            # nothing left to do: the summary of the checkpoint's state (a resumed pipeline)
            phase.completed = True
            return phase.summary(None, t_start), model
    else:
        LOG.info(
            "coiling: mesh %d x %d, %d dofs on %d rank(s), predictor %s, to %g rad",
            res.along,
            res.across,
            global_size(model.model.W),
            comm.size,
            model.predictor,
            phase.target,
        )
    summary = run_phase(phase, directory, config, comm, model.model, restart, progress, t_start)
    return summary, model
