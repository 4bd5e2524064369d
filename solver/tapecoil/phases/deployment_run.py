"""The deployment run: time steps from release to the deployed state, a history row per step.

:class:`DeploymentRun` steps a :class:`~tapecoil.phases.deployment.DeploymentProblem` in time
(generalized-alpha, adaptive steps with cut-back) and records what each step measured
(:mod:`tapecoil.phases.deployment_rows`); :class:`DeploymentPhase` is the run as a phase of the
one runner (:mod:`tapecoil.phases.runner`), and :func:`run_deployment` runs it into a results
directory.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.core.dofs import global_size
from tapecoil.core.stepping import ContinuationError
from tapecoil.measures.deployment import deployment_measures, root_load_peaks
from tapecoil.phases.deployment import (
    DeploymentProblem,
    read_deployment_checkpoint,
    write_deployment_checkpoint,
)
from tapecoil.phases.deployment_rows import DeploymentRows
from tapecoil.phases.runner import LOG, Phase, run_phase
from tapecoil.phases.stepped import SteppedRun
from tapecoil.phases.tape_on_hub import TapeOnHub
from tapecoil.phases.time_loop import Deployed, TimeStepper, energy_refusal, step_in_time, time_legs


@dataclass
class DeploymentResult:
    history: list[dict] = field(default_factory=list)
    completed: bool = False
    message: str = ""


class DeploymentRun(SteppedRun):
    """Time stepping from release to ``deployment.lambda_end`` (or ``deployment.t_end``).

    Steps start at ``deployment.dt`` and, with ``deployment.error_tolerance`` set, are sized
    by their estimated local error (:meth:`DeploymentProblem.step_error`); they grow by at most
    ``solver.grow`` and only after easy solves, up to ``max_dt``; a step that fails is cut
    back (``solver.cutback``, ``solver.max_cutbacks``), as in the load stepping.
    ``on_step(row)`` is called on every rank after each step with its row
    (:class:`~tapecoil.phases.deployment_rows.DeploymentRows`).
    """

    def __init__(self, model: DeploymentProblem, on_step=None, max_dt: float | None = None, stop=None):
        super().__init__(DeploymentResult(), on_step, stop)
        self.m = model
        d = model.config.deployment
        self.max_dt = max_dt if max_dt is not None else d.max_dt
        self.rows = DeploymentRows(model)
        self.time = 0.0
        self.next_step = None  # the step to try next within the current phase (for a restart)
        self._restored = False

    def restart_state(self) -> dict:
        """What, besides the model's state, the time stepping needs to go on as if never stopped."""
        return {
            "time": self.time,
            "next_step": self.next_step,
            **self.m.hub_state(),
            **self.rows.restart_state(),
            **self._history_state(),
        }

    def restore(self, state: dict) -> None:
        """Continue from :meth:`restart_state` (the model restored from the same checkpoint)."""
        self.time = state["time"]
        self.next_step = state["next_step"]
        self.rows.restore(state)
        self.m.restore_hub(state)
        self._restore_history(state)
        self._restored = True

    def run(self) -> DeploymentResult:
        """Step from release (or the restored time) until lambda_end, t_end or a failure.

        :class:`~tapecoil.core.interrupt.Interrupted` (a stop signal) propagates, the state being
        the last converged one.
        """
        m = self.m
        d = m.config.deployment
        ti = m.integrator
        if not self._restored:
            m.initial_acceleration()
            self._record(self.rows.row(0.0, None))
        alpha_f = ti.parameters.alpha_f

        def set_step(dt, target):
            ti.set_step(dt)
            m.hold.release(target - alpha_f * dt)  # the hold at the level of the internal forces

        def refusal():
            # too deep into the hub or the turns, or a spurious root that made energy
            reason = m.tape.penetration_refusal()
            if reason is not None:
                return reason
            last = self.result.history[-1]
            start = (
                last["strain_energy"]
                + last["contact_energy"]
                + last["friction_energy"]
                + last["kinetic_energy"]
            )
            return energy_refusal(start, m.step_energy(), m.step_work(), self.rows.stowed_energy)

        stepper = TimeStepper(m.model.q, m.solve, set_step, m.predict, m.step_error, refusal)

        def converged(step, end):
            self.rows.add_step_work()
            m.advance()
            self.time = step.load
            # a phase that ends here hands over to the next one, which starts afresh
            self.next_step = step.next_step if step.load < end else None
            self.rows.add_update_energy(m.update())
            row = self._record(self.rows.row(step.load, step))
            if row["lambda"] >= d.lambda_end:
                raise Deployed
            self._check_stop(m.comm)

        legs = time_legs(m.hold.release_time, d.t_end, d.dt, self.max_dt)
        try:
            step_in_time(m.config, legs, self, lambda: stepper, converged)
            self.result.message = f"t_end = {d.t_end:g} s reached before lambda = {d.lambda_end:g}"
        except Deployed:
            self.result.completed = True
        except ContinuationError as err:
            # the state is the last converged one (the continuation restored it)
            self.result.message = str(err)
        return self.result


class DeploymentPhase(Phase):
    """Deployment as a phase of :func:`~tapecoil.phases.runner.run_phase`: release, then time
    steps to ``deployment.lambda_end`` or ``t_end``; measures of the deployed fraction against
    time (:mod:`tapecoil.measures.deployment`)."""

    name, checkpoint_name, unit = "deployment", "deployed", "s"

    def __init__(self, model: DeploymentProblem, restart: dict | None = None, stop=None):
        super().__init__()
        self.model = model
        self.target = model.config.deployment.t_end
        self.run = DeploymentRun(model, stop=stop)
        self.run.on_step = self._on_step
        if restart is not None:
            self.run.restore(restart)
        self.history = self.run.result.history

    def _on_step(self, row: dict) -> None:
        if self.on_row is not None:
            self.on_row(row)

    def position(self) -> float:
        return self.run.time

    def restart_state(self) -> dict:
        return self.run.restart_state()

    def checkpoint_meta(self) -> dict:
        return {"hub_angle": self.model.hub_angle, "tension": 0.0}

    def write_checkpoint(self, path: Path, meta: dict) -> None:
        write_deployment_checkpoint(self.model, path, meta)

    def progress(self, row: dict) -> tuple[float, float, int, str, bool]:
        return (
            row["time"],
            row["step"],
            row["newton_iterations"],
            f" lambda {row['lambda']:.3f}",
            row["step"] > 0,
        )

    def advance(self) -> None:
        result = self.run.run()
        self.completed, self.message = result.completed, result.message

    def end_log(self, summary: dict) -> str:
        run = summary["run"]
        return (
            f"deployment {'completed' if self.completed else 'ended'} at t = {summary['time']:.6g} s, "
            f"lambda = {summary['lambda']:.4f}: {run['steps']} steps, {run['newton_iterations']} Newton "
            f"iterations, {run['wall_time']:.1f} s"
        )

    def summary(self, interrupted, t_start: float) -> dict:
        """The deployment phase's summary: measures against the theory and the run's figures."""
        model, history = self.model, self.history
        comm, res = model.comm, model.tape.strip.resolution
        timing = model.solver.timing_per_iteration()
        return {
            **deployment_summary(self, interrupted, model.config, model.rho_inf, model.scheme),
            # the peaks of the force [N], moment and torque [N m] the tape puts on the hub at the root
            **root_load_peaks(history),
            "run": {
                "ranks": comm.size,
                "dofs": global_size(model.model.W),
                "mesh": f"{res.along} x {res.across}",
                **step_figures(history),
                # this process's, including the attempts that failed and were cut back
                "newton_iterations_total": int(model.solver.timings["iterations"]),
                "max_penetration": max(r["max_penetration"] for r in history),
                "wall_time": history[-1]["wall_time"],
                "process_wall_time": time.perf_counter() - t_start,
                "assembly_per_iteration": timing["assembly"],
                "linear_solve_per_iteration": timing["linear_solve"],
                # of which the turns' real contact's own (0 where it is a form: the spiral)
                "contact_per_iteration": timing["terms"],
            },
        }


def deployment_summary(phase: Phase, interrupted, config: Config, rho_inf: float, scheme: str) -> dict:
    """The head of a deployment phase's summary (either model's): its state, where it ended, the
    scheme, and the measures against the theory from its history."""
    history = phase.history
    return {
        "completed": phase.completed,
        "message": phase.message,
        "interrupted": None if interrupted is None else interrupted.name,
        "time": history[-1]["time"],
        "lambda": history[-1]["lambda"],
        "rho_inf": rho_inf,
        "scheme": scheme,
        "measures": deployment_measures(config, history),
    }


def step_figures(history: list[dict]) -> dict:
    """A deployment history's steps (the rows after the release's): their count, Newton
    iterations, cut-backs, rejected attempts, smallest and largest step [s]."""
    steps = history[1:]
    return {
        "steps": len(steps),
        "newton_iterations": int(sum(r["newton_iterations"] for r in steps)),
        "cutbacks": int(sum(r["cutbacks"] for r in steps)),
        "rejected_steps": int(sum(r["rejected_steps"] for r in steps)),
        "smallest_step": min((r["step"] for r in steps), default=0.0),
        "largest_step": max((r["step"] for r in steps), default=0.0),
    }


def run_deployment(
    config: Config,
    directory: str | Path,
    comm=MPI.COMM_WORLD,
    stowed: str | Path | None = None,
    tape: TapeOnHub | None = None,
    progress: bool = True,
    stop=None,
    resume: str | Path | None = None,
) -> tuple[dict, DeploymentProblem]:
    """Deploy from the stowed state, writing into ``directory``; returns the phase summary and model.

    The start is the stowed checkpoint directory ``stowed``, the in-memory ``tape`` (a coiling
    run's, in its stowed state), or, with ``resume``, a deployment checkpoint (deployed/) to
    continue from as if never stopped. ``directory`` receives deployment_history.csv (a row per
    step), deployment.bp and snapshots/ (every ``output.vtx_every`` steps and the last state)
    and deployed/ (the checkpoint: the latest converged state, every ``output.checkpoint_every``
    steps and at the end). ``stop``: as in :func:`tapecoil.phases.coiling_run.run_coiling`.
    """
    t_start = time.perf_counter()
    restart = None
    if resume is not None:
        model, meta = read_deployment_checkpoint(resume, config, comm)
        restart = meta["run"]
    else:
        if tape is None:
            if stowed is None:
                raise ValueError("deployment needs a stowed checkpoint directory or a stowed tape")
            tape, _ = TapeOnHub.read_checkpoint(stowed, config, comm)
        model = DeploymentProblem(tape, config)
    d = config.deployment
    phase = DeploymentPhase(model, restart, stop)
    if restart is not None:
        LOG.info("deployment resumed from %s at t = %.6g s", resume, phase.run.time)
        if meta["completed"]:
            # nothing left to do: the summary of the checkpoint's state (a resumed pipeline)
            phase.completed = True
            return phase.summary(None, t_start), model
    else:
        LOG.info(
            "deployment: %s scheme, rho_inf = %g, to lambda = %g", model.scheme, model.rho_inf, d.lambda_end
        )
    summary = run_phase(phase, directory, config, comm, model.model, restart, progress, t_start)
    return summary, model
