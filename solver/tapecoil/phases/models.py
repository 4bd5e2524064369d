"""The tape's model chosen once for a run: the full shell or the shell-beam hybrid, each with its
phases' entry points (coil, pay out, deploy). Which model wrote a checkpoint is its tag
(:mod:`tapecoil.phases.model_tag`), read by the phases that restore it.

:func:`for_config` is the one place outside ``config/`` that reads ``config.model.kind``; a run
calls the chosen model's methods and never asks which model it holds. A model's coiling hands
on a :class:`Coiled` (what the later phases of the same run start from), None when the run did
not coil.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from tapecoil.config import Config
from tapecoil.core.checkpoint import read_meta
from tapecoil.phases.coiling import CoilingProblem
from tapecoil.phases.coiling_run import run_coiling
from tapecoil.phases.deployment_run import run_deployment
from tapecoil.phases.hybrid_coiling import HybridCoiling
from tapecoil.phases.hybrid_coiling_run import coil_again, run_hybrid_coiling
from tapecoil.phases.hybrid_deployment_run import run_hybrid_deployment
from tapecoil.phases.hybrid_payout import hybrid_coil_from, run_hybrid_payout
from tapecoil.phases.payout import run_payout
from tapecoil.phases.runner import LOG


@dataclass
class Coiled:
    """A coiling's result that the run's later phases start from: the full shell's
    :class:`CoilingProblem` and, for the hybrid, its own coiled state (None where a resumed
    coiling's checkpoint does not hold it, and always for the full shell)."""

    model: CoilingProblem
    hybrid: HybridCoiling | None = None


@dataclass
class TapeModelRun:
    """What every phase of one run takes, whichever the model: the configuration, the results
    ``directory``, the communicator, whether to show progress, and the run's stop signals."""

    config: Config
    directory: Path
    comm: object
    progress: bool
    stop: object


class ShellModel(TapeModelRun):
    """The Naghdi shell over the whole tape: every phase from the stowed checkpoint's full shell."""

    kind = "shell"

    def coil(self, resume) -> tuple[dict, Coiled]:
        """:func:`~tapecoil.phases.coiling_run.run_coiling`: the summary and the coiled tape."""
        summary, model = run_coiling(
            self.config, self.directory, self.comm, resume=resume, progress=self.progress, stop=self.stop
        )
        return summary, Coiled(model)

    def pay_out(self, coiled: Coiled | None, stowed, resume) -> dict:
        """:func:`~tapecoil.phases.payout.run_payout` from ``coiled`` (this run's coil) or ``stowed``."""
        summary, _ = run_payout(
            self.config,
            self.directory,
            self.comm,
            stowed=stowed,
            model=None if coiled is None else coiled.model,
            progress=self.progress,
            stop=self.stop,
            resume=resume,
        )
        return summary

    def deploy(self, coiled: Coiled | None, stowed, resume) -> dict:
        """:func:`~tapecoil.phases.deployment_run.run_deployment` from ``coiled`` or ``stowed``."""
        summary, _ = run_deployment(
            self.config,
            self.directory,
            self.comm,
            stowed=stowed,
            tape=None if coiled is None else coiled.model.tape,
            progress=self.progress,
            stop=self.stop,
            resume=resume,
        )
        return summary


class HybridModel(TapeModelRun):
    """The shell-beam hybrid: a shell window on the beam. Its payout and deployment start from its
    own coiled state, which only its own coiling (or that coiling's stowed checkpoint) holds."""

    kind = "hybrid"

    def coil(self, resume) -> tuple[dict, Coiled]:
        """:func:`~tapecoil.phases.hybrid_coiling_run.run_hybrid_coiling`: the summary and the
        coiled tape (the full shell settled, and the hybrid's own state)."""
        summary, model, coiling = run_hybrid_coiling(
            self.config, self.directory, self.comm, resume=resume, progress=self.progress, stop=self.stop
        )
        return summary, Coiled(model, coiling)

    def pay_out(self, coiled: Coiled | None, stowed, resume) -> dict:
        """:func:`~tapecoil.phases.hybrid_payout.run_hybrid_payout` from the hybrid's own coil."""
        if resume is None:  # a resumed payout's checkpoint holds its hybrid
            coiled = self.start(coiled, stowed, "payout")
        return run_hybrid_payout(
            self.config,
            self.directory,
            self.comm,
            None if coiled is None else coiled.model,
            None if coiled is None else coiled.hybrid,
            progress=self.progress,
            stop=self.stop,
            resume=resume,
        )

    def deploy(self, coiled: Coiled | None, stowed, resume) -> dict:
        """:func:`~tapecoil.phases.hybrid_deployment_run.run_hybrid_deployment` from the hybrid's
        own coil (a completed deployment's checkpoint needs none: its summary is read again)."""
        done = resume is not None and read_meta(resume).get("completed")
        if coiled is None or not done:
            coiled = self.start(coiled, stowed, "deployment")
        return run_hybrid_deployment(
            self.config,
            self.directory,
            coiled.model,
            coiled.hybrid,
            self.comm,
            progress=self.progress,
            stop=self.stop,
            resume=resume,
        )

    def start(self, coiled: Coiled | None, stowed, phase: str) -> Coiled:
        """The full shell and the hybrid's own coil that the hybrid's ``phase`` (after the coiling)
        starts from: the run's own ``coiled``; a phase alone's from the hybrid coiling's
        ``stowed`` checkpoint; computed again where a resumed coiling's checkpoint does not hold
        the hybrid's state (another model's, or an older one's)."""
        if coiled is None:
            return Coiled(*hybrid_coil_from(stowed, self.config, self.comm))
        if coiled.hybrid is None:
            LOG.warning(
                "the hybrid's %s starts from the hybrid's own coiled state, which the stowed "
                "checkpoint does not hold: coiling with the hybrid again",
                phase,
            )
            return Coiled(coiled.model, coil_again(self.config, self.comm))
        return coiled


MODELS = {model.kind: model for model in (ShellModel, HybridModel)}


def for_config(config: Config, directory: Path, comm, progress: bool, stop) -> ShellModel | HybridModel:
    """The model ``config.model.kind`` names, for one run into ``directory`` (the one place
    outside config/ that reads the kind; config has checked it is one of :data:`MODELS`)."""
    return MODELS[config.model.kind](config, directory, comm, progress, stop)
