"""A driven hub paying the tape out of the coil: the hub turned back, the free end held in tension.

The way a motorised deployer extends a boom, quasi-static: from the stowed state the hub turns
back (:meth:`CoilingRun.coil` from the stowed angle down) while the pull at the free end is held
(``payout.tension``), until the hub's angle is the one whose mid-surface spiral holds
(1 - payout.lambda_end) L. Without friction the path is the coiling's, reversed.

Each step's row is the coiling's (:mod:`tapecoil.phases.coiling_rows`), which reads the axial
force across the tape's sections (:mod:`tapecoil.measures.section_forces`) independently of the
contact that loads them:

- ``coiling_tension_outer``: T - N on the outermost turn, 1 to 3 rad of winding behind the
  tangent point (:data:`~tapecoil.measures.payout.OUTER_STATION`), where the section lies on
  the coil. By the configurational force balance (physics brief Sec. 5) the plate law puts it
  at Eq. 2.6 at that turn's mid-surface radius, which is Eq. 4.5 with the coil's growing
  radius: the tension the driven hub must hold for the coil to stay wound as it pays out.
- ``coiling_tension`` (the coiling's): T - N at the root, where the clamp holds the whole width
  flat (docs/notes/deployment.md compares the two readings).

The hub torque (from the root's reactions) is compared with steady coiling, rho (T + b w(rho))
with rho the outermost turn's mid-surface radius (:func:`tapecoil.measures.payout.payout_measures`).
"""

from __future__ import annotations

import time
from pathlib import Path

from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import Config, ConfigError
from tapecoil.core.dofs import global_size
from tapecoil.measures.payout import payout_measures
from tapecoil.phases.coiling import CoilingProblem, read_checkpoint
from tapecoil.phases.coiling_run import CoilingRun, HubTurningPhase
from tapecoil.phases.runner import LOG, run_phase


def payout_angle(config: Config) -> float:
    """The hub angle [rad] at which the coil holds (1 - payout.lambda_end) L: the payout's end."""
    tp = config.tape
    return theory.rotation_for_coiled_length((1 - config.payout.lambda_end) * tp.L, config.hub.radius, tp.h)


def check_payout(config: Config, stowed_angle: float) -> None:
    """Refuse a payout that would not turn the hub back from ``stowed_angle`` (before computing)."""
    target = payout_angle(config)
    if target >= stowed_angle:
        raise ConfigError(
            f"payout.lambda_end = {config.payout.lambda_end:g} is already reached in the stowed state "
            f"(hub angle {stowed_angle:.4g} rad; paying out to it stops at {target:.4g} rad): "
            "choose a larger deployed fraction"
        )


class PayoutReport:
    """What a payout phase reports, whichever model turns its hub back: its progress, its end's
    log line and its summary. The phase sets ``start``, ``target`` (hub angles [rad]), ``pull``
    [N] and a ``history`` of payout rows, and its ``model`` is the full shell (in the payout's
    state)."""

    def progress(self, row: dict) -> tuple[float, float, int, str, bool]:
        return row["hub_angle"], row["step"], row["newton_iterations"], f" lambda {row['lambda']:.3f}", True

    def end_log(self, summary: dict) -> str:
        line = super().end_log(summary)
        return line + f", lambda {self.history[-1]['lambda']:.3f}" if self.history else line

    def summary(self, interrupted, t_start: float) -> dict:
        return {
            "completed": self.completed,
            "message": self.message,
            "interrupted": None if interrupted is None else interrupted.name,
            "hub_angle": self.model.root.angle,
            "start_hub_angle": self.start,
            "target_hub_angle": self.target,
            "tension": self.pull,
            "measures": payout_measures(self.model.config, self.history),
            "run": self.run_figures(len(self.history), t_start),
        }


class PayoutPhase(PayoutReport, HubTurningPhase):
    """The driven hub's payout as a phase of :func:`~tapecoil.phases.runner.run_phase`."""

    name, checkpoint_name = "payout", "paid_out"

    def __init__(self, model: CoilingProblem, stop=None, restart: dict | None = None):
        super().__init__(model)
        config = model.config
        # a restart goes on from the stopped payout's state towards the same end
        self.start = model.root.angle if restart is None else restart["start_hub_angle"]
        check_payout(config, self.start)
        self.target = payout_angle(config)
        self.pull = config.payout.tension or config.coiling.tension
        self.run = CoilingRun(model, stop=stop, max_step=config.payout.max_step or None)
        self.run.on_step = self._on_step
        if restart is not None:
            self.run.restore(restart)
        self.history = self.run.result.history

    def restart_state(self) -> dict:
        return {**self.run.restart_state(), "start_hub_angle": self.start}

    def _on_step(self, row: dict) -> None:
        row["phase"] = "payout"
        if self.on_row is not None:
            self.on_row(row)

    def advance(self) -> None:
        self.model.tension.value = self.pull
        self.run.coil(self.target, start_angle=self.model.root.angle, first_step=self.run.next_step)
        self.completed = True


def run_payout(
    config: Config,
    directory: str | Path,
    comm=MPI.COMM_WORLD,
    stowed: str | Path | None = None,
    model: CoilingProblem | None = None,
    progress: bool = True,
    stop=None,
    resume: str | Path | None = None,
) -> tuple[dict, CoilingProblem]:
    """Pay the tape out from the stowed state into ``directory``; returns the summary and model.

    The start is the coiling ``model`` in its stowed state, or the stowed checkpoint ``stowed``;
    ``resume``: a payout's own checkpoint (paid_out/) to go on from as if never stopped.
    ``directory`` receives payout_history.csv, payout.bp, snapshots and paid_out/ (the latest
    converged state, every ``output.checkpoint_every`` steps and at the end).
    """
    t_start = time.perf_counter()
    restart = None
    if resume is not None:
        model, meta = read_checkpoint(resume, config, comm)
        restart = meta.get("run")
        if meta.get("phase") != "payout" or restart is None:
            raise ValueError(f"{resume} holds no payout restart state")
    elif model is None:
        if stowed is None:
            raise ValueError("a payout needs a stowed checkpoint directory or a stowed coiling model")
        model, _ = read_checkpoint(stowed, config, comm)
    phase = PayoutPhase(model, stop, restart)
    if restart is not None and meta["completed"]:
        phase.completed = True  # nothing left to do: the summary of the checkpoint's state
        return phase.summary(None, t_start), model
    LOG.info(
        "payout: from %.6g rad to %.6g rad (lambda = %g), pull %g N, %d dofs on %d rank(s)",
        phase.start,
        phase.target,
        config.payout.lambda_end,
        phase.pull,
        global_size(model.model.W),
        comm.size,
    )
    summary = run_phase(phase, directory, config, comm, model.model, restart, progress, t_start)
    return summary, model
