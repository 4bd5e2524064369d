"""One runner for every phase: resume, per-step output, checkpoints, stops, histories, summary.

A phase (coiling, deployment, ...) is its loads, its stepping and its measures; what a run does
around them is the same for each: continue from a checkpoint as if never stopped, write VTX and
surface snapshots and periodic checkpoints as steps converge, stop cleanly on a signal, write
the history CSV and the final checkpoint, and summarise. A phase implements :class:`Phase`;
:func:`run_phase` does the rest.
"""

from __future__ import annotations

import logging
import time
from abc import ABC, abstractmethod
from pathlib import Path

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.core.interrupt import Interrupted
from tapecoil.core.output import write_csv
from tapecoil.core.stepping import ContinuationError

LOG = logging.getLogger("tapecoil")


def progress_bar(comm, total: float, label: str, unit: str):
    """A tqdm bar on rank 0 (None elsewhere, or when tqdm is missing)."""
    if comm.rank != 0:
        return None
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is a dependency
        return None
    return tqdm(
        total=round(total, 4),
        disable=None,  # no bar in logs (not a terminal)
        desc=label,
        unit=unit,
        bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} " + unit + " [{elapsed}<{remaining}] {postfix}",
    )


class PhaseOutput:
    """Per-step output of a phase (coiling or deployment): VTX and surface snapshots every
    ``output.vtx_every`` steps, a checkpoint every ``output.checkpoint_every`` steps, the progress
    bar, a log line.

    ``checkpoint`` is the phase's own writer (collective), set by the caller. ``restart`` (the
    restart state of a checkpoint) continues the step count, the snapshot numbering and, in a new
    VTX file (``<phase>-2.bp``, ...), the ParaView series. Call :meth:`step` after each converged
    step on every rank, :meth:`close` at the end.
    """

    def __init__(
        self,
        directory: Path,
        model,
        phase: str,
        config: Config,
        comm,
        total,
        unit,
        progress=True,
        restart=None,
    ):
        from tapecoil.core.output import ShellWriter

        self.phase, self.comm, self.unit = phase, comm, unit
        self.output = config.output
        self.count = restart["output_count"] if restart else 0
        path = directory / f"{phase}.bp"
        if restart:  # keep the series written before the stop
            number = 2
            while comm.bcast(path.exists() if comm.rank == 0 else None, root=0):
                path, number = directory / f"{phase}-{number}.bp", number + 1
        self.writer = ShellWriter(
            model,
            path,
            snapshots=directory / "snapshots",
            phase=phase,
            first_index=self.count // self.output.vtx_every,
        )
        self.bar = progress_bar(comm, total, phase, unit) if progress else None
        self.checkpoint = None
        # wall time spent writing VTX, snapshots and checkpoints [s] (the summary's output_time)
        self.seconds = 0.0

    def step(self, value: float, step: float, iterations: int, extra: str = "", checkpoint=True) -> None:
        """After a converged step at ``value`` (hub angle or time); ``checkpoint``: one may be written."""
        self.count += 1
        t0 = time.perf_counter()
        if self.count % self.output.vtx_every == 0:
            self.writer.write(value)
        if checkpoint and self.checkpoint is not None and self.count % self.output.checkpoint_every == 0:
            self.checkpoint()
        self.seconds += time.perf_counter() - t0
        if self.bar is not None:
            self.bar.n = round(value, 4)
            self.bar.set_postfix_str(f"step {step:.3g} {self.unit} its {iterations}{extra}")
        LOG.info("%s %s = %.6g step %.4g its %d%s", self.phase, self.unit, value, step, iterations, extra)

    def close(self, value: float) -> None:
        if self.bar is not None:
            self.bar.close()
        t0 = time.perf_counter()
        self.writer.write(value)
        self.writer.close()
        self.seconds += time.perf_counter() - t0


class Phase(ABC):
    """What :func:`run_phase` needs of a phase.

    Class attributes: ``name`` (files ``<name>_history.csv``, ``<name>.bp``), ``checkpoint_name``
    (the checkpoint directory in the results directory) and ``unit`` of the phase's progress
    variable (hub angle, time). Set by the phase: ``target`` (where the phase ends, in ``unit``),
    ``history`` (a row per converged step), ``completed``, ``message``, and ``on_row``, which the
    phase calls with each new history row.
    """

    name: str
    checkpoint_name: str
    unit: str

    def __init__(self):
        self.target = 0.0
        self.history: list[dict] = []
        self.completed = False
        self.message = ""
        self.on_row = None

    @abstractmethod
    def position(self) -> float:
        """Where the phase is now, in ``unit``."""

    @abstractmethod
    def restart_state(self) -> dict:
        """What, besides the state in the checkpoint, the phase needs to go on as if never stopped."""

    @abstractmethod
    def checkpoint_meta(self) -> dict:
        """The phase's own entries of a checkpoint's meta (the hub angle, the pull, ...)."""

    @abstractmethod
    def write_checkpoint(self, path: Path, meta: dict) -> None:
        """Write the phase's checkpoint with ``meta`` (collective)."""

    @abstractmethod
    def advance(self) -> None:
        """Compute to the end. May raise ContinuationError (stopped, state: the last converged
        one) or Interrupted (a stop signal, after the current step)."""

    @abstractmethod
    def progress(self, row: dict) -> tuple[float, float, int, str, bool]:
        """(value, step, Newton iterations, extra text, whether a checkpoint may follow) of a row."""

    @abstractmethod
    def summary(self, interrupted: Interrupted | None, t_start: float) -> dict:
        """The phase's summary: completed, message, interrupted, measures, run figures."""

    def finish(self, directory: Path) -> None:  # noqa: B027 - optional hook
        """Write the phase's own final files into ``directory`` (collective); none by default."""

    def end_log(self, summary: dict) -> str:
        """The log line of the phase's end."""
        run = summary["run"]
        state = "completed" if self.completed else "ended"
        return (
            f"{self.name} {state} at {self.position():.6g} {self.unit}: {run['steps']} steps, "
            f"{run['newton_iterations']} Newton iterations, {run['wall_time']:.1f} s"
        )


def run_phase(
    phase: Phase,
    directory: str | Path,
    config: Config,
    comm,
    model,
    restart: dict | None = None,
    progress: bool = True,
    t_start: float | None = None,
) -> dict:
    """Run ``phase`` into ``directory`` and return its summary.

    ``model`` is the shell written to VTX and the snapshots; ``restart`` the restart state of
    the checkpoint the phase was restored from (None for a fresh start): output numbering and
    the ParaView series continue from it. ``t_start``: when the phase's process work began
    (for the summary's process wall time; default now).
    """
    directory = Path(directory)
    t_start = time.perf_counter() if t_start is None else t_start
    out = PhaseOutput(directory, model, phase.name, config, comm, phase.target, phase.unit, progress, restart)
    checkpoint_path = directory / phase.checkpoint_name

    def meta(completed: bool) -> dict:
        state = {**phase.restart_state(), "output_count": out.count}
        return {"phase": phase.name, **phase.checkpoint_meta(), "completed": completed, "run": state}

    def on_row(row: dict) -> None:
        value, step, iterations, extra, may_checkpoint = phase.progress(row)
        out.step(value, step, iterations, extra, may_checkpoint)

    if config.output.checkpoint:
        out.checkpoint = lambda: phase.write_checkpoint(checkpoint_path, meta(False))
    phase.on_row = on_row
    interrupted = None
    try:
        phase.advance()
    except ContinuationError as err:
        phase.message = str(err)
        LOG.error("%s stopped: %s", phase.name, err)
    except Interrupted as err:
        interrupted = err
        phase.message = str(err)
        LOG.warning("%s %s at %.6g %s; checkpoint written", phase.name, err, phase.position(), phase.unit)
    out.close(phase.position())
    t0 = time.perf_counter()
    write_csv(directory / f"{phase.name}_history.csv", phase.history, comm)
    if config.output.checkpoint:
        phase.write_checkpoint(checkpoint_path, meta(phase.completed))
    out.seconds += time.perf_counter() - t0
    phase.finish(directory)
    summary = phase.summary(interrupted, t_start)
    if "run" in summary:
        # this process's; the run's wall time includes it
        summary["run"]["output_time"] = comm.allreduce(out.seconds, op=MPI.MAX)
    LOG.info("%s", phase.end_log(summary))
    return summary
