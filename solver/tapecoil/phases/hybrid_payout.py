"""A driven hub's payout with the shell-beam hybrid: the hub turned back from the hybrid's own
coil, the free end held in tension, the shell window following the lift-off down the coil.

The path is the hybrid's coiling reversed (:meth:`~tapecoil.phases.hybrid_coiling.HybridCoiling.coil`
to a smaller hub angle): once the lift-off has come within ``window_behind`` of the window's
start, the window moves towards the root, the flattened beam on the coil becoming shell (its
placed sections settled on the coil, :func:`~tapecoil.models.window_settling.settle_placed`) and
the shell beyond the window's new end becoming arc beam, the guide and the pull on it once the
window has left the free end. The pull (``payout.tension``, else ``coiling.tension``) acts from
the payout's first step, as on the full shell (:mod:`tapecoil.phases.payout`), whose rows,
measures and summary this phase shares: the outer turn's and the root's coiling tension and
the hub torque from the root's reaction, against the laws of a flattened coil.

As in the hybrid's coiling (:mod:`tapecoil.phases.hybrid_coiling_run`), a full shell of the
same tape is kept in the hybrid's configuration after every step, for the snapshots and the
geometric measures; its checkpoint (paid_out/) carries the hybrid's own state beside it, from
which a stopped payout goes on as if never stopped.
"""

from __future__ import annotations

import time
from pathlib import Path

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.core.checkpoint import read_meta, read_tables
from tapecoil.phases.coiling import CoilingProblem, read_checkpoint
from tapecoil.phases.hybrid_coiling import HybridCoiling
from tapecoil.phases.hybrid_coiling_run import HybridCoilingPhase
from tapecoil.phases.model_tag import by_hybrid
from tapecoil.phases.payout import PayoutReport, check_payout, payout_angle
from tapecoil.phases.runner import LOG, run_phase

__all__ = ["HybridPayoutPhase", "run_hybrid_payout"]


class HybridPayoutPhase(PayoutReport, HybridCoilingPhase):
    """The hybrid's payout (see the module) from ``coiling`` at its hub angle, ``model`` the full
    shell kept in its configuration; ``restart``: a stopped payout's restart state."""

    name, checkpoint_name = "payout", "paid_out"

    def __init__(
        self,
        config: Config,
        comm,
        model: CoilingProblem,
        coiling: HybridCoiling,
        stop=None,
        restart: dict | None = None,
        completed: bool = False,
    ):
        super().__init__(config, comm, model, restart, stop, coiling=coiling, completed=completed)
        # a restart goes on from the stopped payout's state towards the same end
        self.start = coiling.angle if restart is None else restart["start_hub_angle"]
        check_payout(config, self.start)
        self.target = payout_angle(config)
        self.pull = config.payout.tension or config.coiling.tension
        if config.payout.max_step:
            coiling.max_step = config.payout.max_step

    def restart_state(self) -> dict:
        return {**super().restart_state(), "start_hub_angle": self.start}

    def advance(self) -> None:
        self.coiling.set_pull(self.pull)
        self.coiling.coil(
            self.target, on_step=lambda r: self._step("payout", r.hub_angle, r.step, r.iterations)
        )
        self.completed = True

    def finish(self, directory: Path) -> None:
        """None: the payout writes no coil's cells (the shell's payout writes none either)."""


def hybrid_coil_from(
    stowed: str | Path, config: Config, comm=MPI.COMM_WORLD
) -> tuple[CoilingProblem, HybridCoiling]:
    """The full shell and the hybrid's own coil of the stowed checkpoint of a completed coiling by
    the hybrid (``tapecoil coil --model hybrid``: its tables hold the hybrid's state), which the
    hybrid's payout and deployment alone start from; refused, before anything is computed, for
    any other checkpoint (collective)."""
    from tapecoil.core.checkpoint import is_checkpoint

    meta = read_meta(stowed) if is_checkpoint(Path(stowed)) else {}
    restart = meta.get("run") or {}
    ours = meta.get("completed") and by_hybrid(restart) and restart.get("coiling")
    tables = read_tables(stowed) if ours else None
    if tables is None:
        raise ValueError(
            f"{stowed} is not the stowed checkpoint of a completed coiling by the hybrid, which the "
            "hybrid's payout and deployment start from (model.kind = 'hybrid'): coil with --model "
            "hybrid first, or use the full shell (model.kind = 'shell')"
        )
    model, _ = read_checkpoint(stowed, config, comm)
    return model, HybridCoiling(config, comm, restart=restart["coiling"], tables=tables)


def run_hybrid_payout(
    config: Config,
    directory: str | Path,
    comm=MPI.COMM_WORLD,
    model: CoilingProblem | None = None,
    coiling: HybridCoiling | None = None,
    progress: bool = True,
    stop=None,
    resume: str | Path | None = None,
) -> dict:
    """Pay the tape out with the hybrid into ``directory`` (the files of
    :func:`~tapecoil.phases.payout.run_payout`); returns the summary. The start is ``coiling``,
    the hybrid's coil at its hub angle, with ``model``, the full shell its coiling kept in its
    configuration; ``resume``: a hybrid payout's own checkpoint (paid_out/) to go on from as if
    never stopped."""
    t_start = time.perf_counter()
    restart = None
    completed = False
    if resume is not None:
        meta = read_meta(resume)
        restart = meta.get("run") or {}
        tables = read_tables(resume)
        if meta.get("phase") != "payout" or not by_hybrid(restart) or tables is None:
            raise ValueError(f"{resume} holds no restart state of the hybrid's payout")
        model, _ = read_checkpoint(resume, config, comm)
        coiling = HybridCoiling(config, comm, restart=restart["coiling"], tables=tables)
        completed = bool(meta.get("completed"))
    elif model is None or coiling is None:
        raise ValueError("the hybrid's payout starts from its own coil: give the coiling and its full shell")
    phase = HybridPayoutPhase(config, comm, model, coiling, stop, restart, completed)
    if completed:
        return phase.summary(None, t_start)  # nothing left to do: the checkpoint's summary
    LOG.info(
        "payout with the hybrid: from %.6g rad to %.6g rad (lambda = %g), pull %g N, window "
        "%.3f-%.3f m on %d rank(s)",
        phase.start,
        phase.target,
        config.payout.lambda_end,
        phase.pull,
        *coiling.hybrid.shell.surface.xi_range[0],
        comm.size,
    )
    return run_phase(phase, directory, config, comm, model.model, restart, progress, t_start)
