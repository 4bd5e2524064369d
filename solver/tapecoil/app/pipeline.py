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
    deployment starting from the coiling's stowed state; each phase by the model that
    ``config.model.kind`` names (:mod:`tapecoil.phases.models`; the hybrid's coiling:
    :mod:`tapecoil.phases.hybrid_coiling_run`, its stowed state the full shell's); "payout" in
    place of "deployment" pays the tape out with a driven hub instead
    (:mod:`tapecoil.phases.payout`; the hybrid's: :mod:`tapecoil.phases.hybrid_payout`, from its
    own coil). With ``model.kind = "hybrid"`` a deployment or payout alone starts from the
    hybrid's coil in the stowed checkpoint of a
    coiling by the hybrid. ``resume``: go on
    from the directory's own checkpoints (stowed/, deployed/, paid_out/) as if the run had never stopped;
    ``coiling_checkpoint``: resume the coiling from that checkpoint instead. A stop signal (see
    :mod:`tapecoil.core.interrupt`) ends the run after its current step with everything written and
    ``summary["interrupted"]`` set. ``report``: make the pictures and report.html (default:
    ``output.report``; rank 0, after the computation).
    """
    from tapecoil.config.model import frictionless_need, hybrid_deployment_need
    from tapecoil.config.params import ConfigError
    from tapecoil.phases.models import for_config

    if "deployment" in phases and "payout" in phases:
        raise ValueError("a run deploys the stowed tape or pays it out, not both")
    need = frictionless_need(config, phases)
    if need is not None:
        raise ConfigError(need)
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
            tape_model = for_config(config, directory, comm, progress, stop)
            coiled = None
            if "coiling" in phases:
                resume_coil = coiling_checkpoint or (
                    own_stowed if resume and is_checkpoint(own_stowed) else None
                )
                out["coiling"], coiled = tape_model.coil(resume_coil)
            deploying = "deployment" in phases and (coiled is None or out["coiling"]["completed"])
            paying_out = "payout" in phases and (coiled is None or out["coiling"]["completed"])
            if paying_out:
                resume_payout = _own_checkpoint(directory / "paid_out", "payout") if resume else None
                out["payout"] = tape_model.pay_out(coiled, stowed, resume_payout)
            if deploying:
                resume_deployment = _own_checkpoint(own_deployed, "deployment") if resume else None
                out["deployment"] = tape_model.deploy(coiled, stowed, resume_deployment)
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
