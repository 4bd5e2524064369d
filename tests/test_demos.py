"""Every demo runs, serially and on two ranks.

The long demos run their smoke variant (``TAPECOIL_DEMO_SMOKE=1``): the same steps on a shorter
problem, the way the DOLFINx and FEniCSx-Shells demos are tested. Serially each demo is a
subprocess, as a user starts it. On two ranks (the test itself under ``mpirun -n 2``) the demo's
script runs in the test's process, where a nested ``mpirun`` could not start.
"""

import json
import os
import runpy
import subprocess
import sys
from pathlib import Path

import pytest

DEMOS = Path(__file__).resolve().parents[1] / "demos"

# demo: (the files it must write under results/, text it must print)
EXPECTED = {
    "theory_report.py": (
        ["theory/deployment_theory.png", "theory/coiling_tension_theory.png"],
        ["0.4426 s", "plots written to"],
    ),
    "tape_fold.py": (
        ["tape_fold-smoke/fold.bp", "tape_fold-smoke/moment_rotation.png", "tape_fold-smoke/summary.json"],
        ["moment plateau / alpha (sqrt(D11 D22) + D12)", "written:"],
    ),
    "sze_semicylinder.py": (
        ["sze_semicylinder-smoke/summary.json", "sze_semicylinder-smoke/load_deflection.png"],
        ["deflection under the load at P = 2000", "written:"],
    ),
    "benchmark.py": (
        [
            "benchmark-coarse-smoke/summary.json",
            "benchmark-coarse-smoke/report.html",
            "benchmark-coarse-smoke/stowed/meta.json",
            "benchmark-coarse-smoke/deployment_history.csv",
        ],
        ["coiling:", "deployment:", "report:"],
    ),
}


def _check_results(directory: Path, demo: str) -> None:
    files, _ = EXPECTED[demo]
    for name in files:
        assert (directory / "results" / name).exists(), name
    if demo == "tape_fold.py":
        summary = json.loads((directory / "results/tape_fold-smoke/summary.json").read_text())
        # the smoke run still passes the snap, the step it exists to exercise
        assert summary["info"]["snap_angle"] is not None
    if demo == "sze_semicylinder.py":
        summary = json.loads((directory / "results/sze_semicylinder-smoke/summary.json").read_text())
        # the whole load reached, the crown pushed towards the axis by about Sze's deflection
        assert summary["path"][-1][0] == pytest.approx(2000.0)
        assert 1.5 < summary["W"] < 1.8
    if demo == "benchmark.py":
        summary = json.loads((directory / "results/benchmark-coarse-smoke/summary.json").read_text())
        assert summary["completed"] and summary["deployment"]["lambda"] == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("demo", sorted(EXPECTED))
def test_demo(demo, tmp_path):
    """The demo as a user runs it (``python3 demos/<demo>``), results under the working directory."""
    env = dict(os.environ, TAPECOIL_DEMO_SMOKE="1", MPLBACKEND="Agg")
    done = subprocess.run(
        [sys.executable, str(DEMOS / demo)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,  # a hang fails the test instead of stopping the suite
    )
    assert done.returncode == 0, done.stderr[-3000:]
    for text in EXPECTED[demo][1]:
        assert text in done.stdout, text
    _check_results(tmp_path, demo)


@pytest.mark.mpi
@pytest.mark.parametrize("demo", sorted(EXPECTED))
def test_demo_on_two_ranks(demo, tmp_path, monkeypatch, capsys):
    """The demo's script on the ranks of this test, in one results directory."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    directory = Path(comm.bcast(str(tmp_path), root=0))
    monkeypatch.chdir(directory)
    monkeypatch.setenv("TAPECOIL_DEMO_SMOKE", "1")
    monkeypatch.setattr(sys, "argv", [str(DEMOS / demo)])
    try:
        runpy.run_path(str(DEMOS / demo), run_name="__main__")
        status = 0
    except SystemExit as exc:  # benchmark.py ends with the run's exit status
        status = exc.code
    # every rank reports before any asserts, so that one rank's failure cannot leave the other
    # waiting in a collective operation
    statuses = comm.allgather(status)
    assert statuses == [0] * comm.size
    out = capsys.readouterr().out
    if comm.rank == 0:
        for text in EXPECTED[demo][1]:
            assert text in out, text
    comm.barrier()
    _check_results(directory, demo)
