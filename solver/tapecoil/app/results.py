"""The results directory of a run: layout, per-step output, log, and the JSON summary.

A run writes into one directory (``--out``)::

    config.toml               the configuration used
    summary.json              every validated quantity (computed, reference, error, tolerance),
                              the run's figures (steps, Newton iterations, DOFs, wall time)
    run.log                   what happened, step by step (rank 0)
    coiling_history.csv       a row per converged load step
    deployment_history.csv    a row per time step
    coiling.bp, deployment.bp ParaView (VTX; Warp By Vector with ``offset``)
    stowed/, deployed/        checkpoints: the latest converged state of each phase (adios4dolfinx)
    snapshots/                the deformed surface at the VTX steps, gathered (for the pictures)
    figures/, report.html     pictures and the report (tapecoil report)

Every rank takes part in the collective steps; files are written by rank 0.
"""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path

from mpi4py import MPI

from tapecoil.config import Config, to_toml
from tapecoil.measures.measure import validation_rows

LOG = logging.getLogger("tapecoil")


def prepare_directory(directory: str | Path, config: Config, comm) -> Path:
    """Create the directory and write the configuration used (collective)."""
    directory = Path(directory)
    if comm.rank == 0:
        directory.mkdir(parents=True, exist_ok=True)
        (directory / "config.toml").write_text(to_toml(config))
    comm.barrier()
    return directory


def start_log(directory: str | Path, comm) -> logging.Handler | None:
    """Log the ``tapecoil`` logger into ``directory``/run.log (appended; rank 0 only)."""
    LOG.setLevel(logging.INFO)
    if comm.rank != 0:
        return None
    handler = logging.FileHandler(Path(directory) / "run.log")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s", "%Y-%m-%d %H:%M:%S"))
    LOG.addHandler(handler)
    return handler


def stop_log(handler: logging.Handler | None) -> None:
    if handler is not None:
        LOG.removeHandler(handler)
        handler.close()


def write_summary(directory: str | Path, summary: dict, comm) -> None:
    """summary.json (rank 0)."""
    if comm.rank == 0:
        (Path(directory) / "summary.json").write_text(json.dumps(summary, indent=2))


def run_summary(phases: dict, started: float, comm=MPI.COMM_WORLD) -> dict:
    """The directory's summary from the phases' summaries ("coiling", "deployment")."""
    from tapecoil import __version__

    rows = []
    if "coiling" in phases:
        rows += validation_rows("coiling", phases["coiling"]["measures"])
    if "deployment" in phases:
        m = phases["deployment"]["measures"]
        rows += validation_rows("deployment", m)
    completed = all(p["completed"] for p in phases.values())
    interrupted = next((p["interrupted"] for p in phases.values() if p.get("interrupted")), None)
    return {
        "tapecoil": __version__,
        "completed": completed,
        "interrupted": interrupted,
        "ranks": comm.size,
        "wall_time": time.perf_counter() - started,
        "validation": rows,
        **phases,
    }
