"""A run in a results directory: coiling and/or deployment, with its log, graceful stops,
summary.json and report. The command line, the demos and the sweeps all run through here.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from mpi4py import MPI

from tapecoil import __version__
from tapecoil.app import results
from tapecoil.config import Config
from tapecoil.core.checkpoint import is_checkpoint, read_meta
from tapecoil.core.interrupt import StopSignals


def run(
    config: Config,
    directory: str | Path,
    phases: tuple[str, ...] = ("coiling", "deployment"),
    comm=MPI.COMM_WORLD,
    resume: bool = False,
    coiling_checkpoint: str | Path | None = None,
    stowed: str | Path | None = None,
    progress: bool = True,
    report: bool | None = None,
    command: str = "run",
) -> dict:
    """Run ``phases`` into ``directory`` and return its summary (also written as summary.json).

    ``phases``: ("coiling",), ("deployment",) (from the checkpoint ``stowed``) or both, the
    deployment starting from the coiling's stowed state; the coiling by ``config.model.kind``'s
    model (the hybrid's: :mod:`tapecoil.phases.hybrid_coiling_run`, its stowed state the full
    shell's); "payout" in place of "deployment" pays
    the tape out with a driven hub instead (:mod:`tapecoil.phases.payout`; the hybrid's:
    :mod:`tapecoil.phases.hybrid_payout`, from its own coil). With ``model.kind = "hybrid"`` a
    deployment or payout alone starts from the hybrid's coil in the stowed checkpoint of a
    coiling by the hybrid. ``resume``: go on
    from the directory's own checkpoints (stowed/, deployed/, paid_out/) as if the run had never stopped;
    ``coiling_checkpoint``: resume the coiling from that checkpoint instead. A stop signal (see
    :mod:`tapecoil.core.interrupt`) ends the run after its current step with everything written and
    ``summary["interrupted"]`` set. ``report``: make the pictures and report.html (default:
    ``output.report``; rank 0, after the computation).
    """
    from tapecoil.config.model import hybrid_deployment_need
    from tapecoil.config.params import ConfigError
    from tapecoil.phases.coiling_run import run_coiling
    from tapecoil.phases.deployment_run import run_deployment
    from tapecoil.phases.hybrid_coiling_run import run_hybrid_coiling
    from tapecoil.phases.hybrid_deployment_run import run_hybrid_deployment
    from tapecoil.phases.hybrid_payout import run_hybrid_payout
    from tapecoil.phases.payout import run_payout

    if "deployment" in phases and "payout" in phases:
        raise ValueError("a run deploys the stowed tape or pays it out, not both")
    hybrid = config.model.kind == "hybrid"
    if "deployment" in phases:
        need = hybrid_deployment_need(config)
        if need is not None:
            raise ConfigError(need)
    started = time.perf_counter()
    directory = results.prepare_directory(directory, config, comm)
    own_stowed, own_deployed = directory / "stowed", directory / "deployed"
    handler = results.start_log(directory, comm)
    try:
        results.LOG.info(
            "tapecoil %s %s: %d rank(s), results in %s", __version__, command, comm.size, directory
        )
        out: dict = {}
        with StopSignals() as stop:
            model = hybrid_coiling = None
            if "coiling" in phases:
                resume_coil = coiling_checkpoint or (
                    own_stowed if resume and is_checkpoint(own_stowed) else None
                )
                coiling_args = (config, directory, comm)
                coiling_kwargs = {"resume": resume_coil, "progress": progress, "stop": stop}
                if hybrid:
                    out["coiling"], model, hybrid_coiling = run_hybrid_coiling(
                        *coiling_args, **coiling_kwargs
                    )
                else:
                    out["coiling"], model = run_coiling(*coiling_args, **coiling_kwargs)
            deploying = "deployment" in phases and (model is None or out["coiling"]["completed"])
            paying_out = "payout" in phases and (model is None or out["coiling"]["completed"])
            resume_payout = _own_checkpoint(directory / "paid_out", "payout") if resume else None
            if paying_out and hybrid:
                if resume_payout is None:  # a resumed payout's checkpoint holds its hybrid
                    model, hybrid_coiling = _hybrid_start(
                        config, comm, model, hybrid_coiling, stowed, "payout"
                    )
                out["payout"] = run_hybrid_payout(
                    config,
                    directory,
                    comm,
                    model,
                    hybrid_coiling,
                    progress=progress,
                    stop=stop,
                    resume=resume_payout,
                )
            elif paying_out:
                out["payout"], _ = run_payout(
                    config,
                    directory,
                    comm,
                    stowed=stowed,
                    model=model,
                    progress=progress,
                    stop=stop,
                    resume=resume_payout,
                )
            if deploying and hybrid:
                resume_deployment = _own_checkpoint(own_deployed, "deployment") if resume else None
                done = resume_deployment is not None and read_meta(resume_deployment).get("completed")
                if model is None or not done:
                    model, hybrid_coiling = _hybrid_start(
                        config, comm, model, hybrid_coiling, stowed, "deployment"
                    )
                out["deployment"] = run_hybrid_deployment(
                    config,
                    directory,
                    model,
                    hybrid_coiling,
                    comm,
                    progress=progress,
                    stop=stop,
                    resume=resume_deployment,
                )
            elif deploying:
                out["deployment"], _ = run_deployment(
                    config,
                    directory,
                    comm,
                    stowed=stowed,
                    tape=None if model is None else model.tape,
                    progress=progress,
                    stop=stop,
                    resume=_own_checkpoint(own_deployed, "deployment") if resume else None,
                )
        from tapecoil.measures.separation import separation_measure

        for phase, phase_summary in out.items():
            separation = separation_measure(directory, phase, comm)
            if separation is not None:
                phase_summary["measures"]["closest_turns"] = separation
        summary = results.run_summary(out, started, comm)
        results.write_summary(directory, summary, comm)
        if (config.output.report if report is None else report) and not summary["interrupted"]:
            make_report(directory, comm)
    finally:
        results.stop_log(handler)
    return summary


def _hybrid_start(config: Config, comm, model, coiling, stowed, phase: str):
    """The full shell and the hybrid's own coil that the hybrid's ``phase`` (after the coiling)
    starts from: the run's own (``model``, ``coiling``); a phase alone's from the hybrid coiling's
    ``stowed`` checkpoint; computed again where a resumed coiling's checkpoint does not hold
    the hybrid's state (another model's, or an older one's)."""
    from tapecoil.phases.hybrid_coiling_run import coil_again
    from tapecoil.phases.hybrid_payout import hybrid_coil_from

    if model is None:
        return hybrid_coil_from(stowed, config, comm)
    if coiling is None:
        results.LOG.warning(
            "the hybrid's %s starts from the hybrid's own coiled state, which the stowed "
            "checkpoint does not hold: coiling with the hybrid again",
            phase,
        )
        coiling = coil_again(config, comm)
    return model, coiling


def _own_checkpoint(path: Path, phase: str) -> Path | None:
    """``path`` if it holds a checkpoint of ``phase`` to resume from, else None."""
    return path if is_checkpoint(path) and read_meta(path).get("phase") == phase else None


def make_report(directory: str | Path, comm=MPI.COMM_WORLD) -> Path | None:
    """Pictures and report.html (rank 0); a failure to draw is logged, not fatal to the run."""
    if comm.rank != 0:
        return None
    try:
        from tapecoil.post.report import write_report

        path = write_report(directory)
        results.LOG.info("report: %s", path)
        return path
    except Exception as exc:  # the results stand without their pictures
        results.LOG.warning("report not made: %r", exc)
        print(f"tapecoil: report not made: {exc!r}", file=sys.stderr)
        return None


def exit_status(summary: dict) -> int:
    """0 when every phase completed, 128 + the signal's number when stopped by one, 1 otherwise."""
    if summary["interrupted"]:
        import signal

        return 128 + int(signal.Signals[summary["interrupted"]])
    return 0 if summary["completed"] else 1
