"""The command line: theory table and JSON, and refusal of a broken configuration."""

import csv
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tapecoil.app.cli import main
from tapecoil.config import load_config


def test_theory_json_numbers(capsys):
    assert main(["theory", "--json"]) == 0
    p = json.loads(capsys.readouterr().out)["predictions"]
    assert p["T_deploy_hub"]["value"] == pytest.approx(0.443, rel=5e-3)
    assert p["T_deploy_ode"]["value"] == pytest.approx(0.436, rel=5e-3)
    assert p["t90_ode"]["value"] == pytest.approx(0.352, rel=5e-3)
    assert p["coiling_tension"]["value"] == pytest.approx(0.384, rel=5e-3)
    assert p["coil_radius"]["value"] == pytest.approx(13.27e-3, rel=5e-3)
    assert p["stored_energy"]["unit"] == "J"


def test_theory_table(capsys):
    assert main(["theory"]) == 0
    out = capsys.readouterr().out
    assert "0.4426 s" in out and "Eq. 2.23" in out
    assert "0.3842 N" in out and "13.27 mm" in out


def test_broken_config_refused(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("[tape]\nnu = 0.7\n")
    assert main(["theory", str(path)]) == 2
    err = capsys.readouterr().err
    assert "tape.nu = 0.7 is out of range: must be in (-1, 0.5)" in err
    assert err.count("\n") == 1


def test_config_command_round_trips(tmp_path, capsys):
    assert main(["config"]) == 0
    path = tmp_path / "c.toml"
    path.write_text(capsys.readouterr().out)
    assert main(["theory", str(path), "--json"]) == 0


@pytest.mark.skipif(shutil.which("tapecoil") is None, reason="console script not installed")
def test_console_script():
    out = subprocess.run(["tapecoil", "theory", "--json"], capture_output=True, text=True, check=True).stdout
    assert json.loads(out)["predictions"]["coiling_tension"]["value"] == pytest.approx(0.3842, rel=1e-3)


def test_coil_refuses_bad_input_before_computing(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("[coiling]\ntension = -1.0\n")
    assert main(["coil", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "coiling.tension" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # nothing was started


def test_coil_refuses_a_hub_angle_longer_than_the_tape(tmp_path, capsys):
    path = tmp_path / "long.toml"
    path.write_text("[coiling]\nhub_angle = 200\n")
    assert main(["coil", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "coiling.hub_angle = 200 rad is more than the tape can coil" in err
    assert err.count("\n") == 1
    assert not (tmp_path / "out").exists()  # nothing was started


@pytest.mark.parametrize(
    ("mesh", "angle", "reason"),
    [
        ("coarse", 37.0, "on this mesh (2.4 elements at the free end"),
        ("default", 37.7, "to bend from the coil's outer turn down onto the guide line"),
    ],
)
def test_coil_refuses_a_hub_angle_that_leaves_the_free_end_no_room(tmp_path, capsys, mesh, angle, reason):
    """A hub angle the tape is long enough for, but whose free part is too short for its end on
    the guide line: refused before computing, with the room left and the room needed (the coarse
    mesh stopped at 37.11 rad, the tape pressed through its outer turn, the default at 37.73)."""
    path = tmp_path / "short_free.toml"
    path.write_text(f"[coiling]\nhub_angle = {angle}\n")
    assert main(["coil", str(path), "--mesh", mesh, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"coiling.hub_angle = {angle:g} rad leaves" in err and reason in err
    assert not (tmp_path / "out").exists()  # nothing was started


def test_run_refuses_a_hybrid_it_cannot_coil_before_computing(tmp_path, capsys):
    path = tmp_path / "equal.toml"
    path.write_text('[coiling]\nsense = "equal"\n')
    assert main(["run", str(path), "--model", "hybrid", "--out", str(tmp_path / "out")]) == 2
    assert "model.kind = 'hybrid' needs coiling.sense = 'opposite'" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # nothing was started


class _Started(Exception):
    """Raised by the stand-in for the pipeline: the command got as far as computing."""


WEAK_PULL = r"coiling\.tension = 0\.1 N is below the 0\.374 N the hub needs \(Eq\. 2\.6"


@pytest.mark.parametrize("command", ["coil", "run"])
def test_coiling_commands_warn_of_a_weak_pull_before_computing(tmp_path, monkeypatch, command):
    """Once, as a ConfigWarning and in run.log, before the run starts (which is stopped there)."""
    import re

    from tapecoil.app import pipeline
    from tapecoil.config import ConfigWarning

    seen = {}

    def started(config, directory, **kwargs):
        seen["warnings"] = [str(w.message) for w in record if issubclass(w.category, ConfigWarning)]
        seen["log"] = (Path(directory) / "run.log").read_text()
        raise _Started

    monkeypatch.setattr(pipeline, "run", started)
    path = tmp_path / "weak.toml"
    path.write_text("[coiling]\ntension = 0.1\n")
    with pytest.warns(ConfigWarning, match=WEAK_PULL) as record, pytest.raises(_Started):
        main([command, str(path), "--out", str(tmp_path / "out"), "--json"])
    assert len(seen["warnings"]) == 1 and re.match(WEAK_PULL, seen["warnings"][0])
    assert len(re.findall("WARNING configuration: " + WEAK_PULL, seen["log"])) == 1


def test_the_weak_pull_warning_is_one_console_line(tmp_path):
    """Printed by tapecoil itself: once DOLFINx has loaded FFCx, Python's display of warnings is
    gone (FFCx sends them to the logging module)."""
    import sys

    path, out = tmp_path / "weak.toml", tmp_path / "out"
    path.write_text("[coiling]\ntension = 0.1\n")
    code = (
        "import sys\n"
        "from tapecoil.app import pipeline\n"
        "from tapecoil.app.cli import main\n"
        "def started(config, directory, **kwargs):\n"
        "    sys.exit(0)\n"
        "pipeline.run = started\n"
        f"sys.exit(main(['coil', {str(path)!r}, '--out', {str(out)!r}]))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    (line,) = done.stderr.splitlines()
    assert line.startswith("tapecoil: warning: coiling.tension = 0.1 N is below the 0.374 N the hub needs")


def test_commands_that_do_not_coil_load_a_weak_pull_quietly(tmp_path, capsys, recwarn):
    from tapecoil.config import ConfigWarning

    path = tmp_path / "weak.toml"
    path.write_text("[coiling]\ntension = 0.1\n")
    assert main(["config", str(path)]) == 0
    assert main(["theory", str(path)]) == 0
    assert not [w for w in recwarn if issubclass(w.category, ConfigWarning)]


def test_coil_short_run_writes_results(tmp_path, capsys):
    import json

    path = tmp_path / "short.toml"
    path.write_text("[tape]\nL = 0.1\n[coiling]\nhub_angle = 0.3\n[mesh]\npreset = 'coarse'\n")
    out = tmp_path / "out"
    assert main(["coil", str(path), "--out", str(out), "--json", "--no-report"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["completed"] and summary["coiling"]["hub_angle"] == 0.3
    assert "deployment" not in summary
    run = summary["coiling"]["run"]
    # the spiral's contact is a form: no time of a term's own; writing the output is a part of the run
    assert run["contact_per_iteration"] == 0.0
    assert 0 < run["output_time"] < run["process_wall_time"]
    for name in (
        "config.toml",
        "coiling_history.csv",
        "summary.json",
        "coiling.bp",
        "stowed/meta.json",
        "run.log",
    ):
        assert (out / name).exists(), name
    rows = {r["quantity"]: r for r in summary["validation"]}
    assert rows["outer_radius"]["tolerance"] == 0.02 and rows["outer_radius"]["phase"] == "coiling"
    assert "coiling rad = 0.3 " in (out / "run.log").read_text()


def test_deploy_refuses_a_missing_checkpoint(tmp_path, capsys):
    assert main(["deploy", str(tmp_path / "nowhere"), "--out", str(tmp_path / "out")]) == 2
    assert "is not a stowed checkpoint" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_verification_case_whose_solve_fails_is_reported_not_raised(monkeypatch, capsys):
    """A case whose continuation gives up fails with its reason on one line; the others run."""
    import tapecoil.verification.cases as cases
    from tapecoil.core.stepping import ContinuationError

    real = cases.run_case

    def failing_fold(name, *args, **kwargs):
        if name == "tape-fold":
            raise ContinuationError("no convergence at load 0.2 (a stand-in for a failed snap)", 0.1)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(cases, "run_case", failing_fold)
    assert main(["verify", "tape-fold"]) == 1
    err = capsys.readouterr().err
    assert "tapecoil: tape-fold stopped: no convergence at load 0.2" in err and "Traceback" not in err
    assert main(["verify", "stress-free", "--json"]) == 0


def test_verify_writes_the_curve_of_a_case_that_follows_a_path(tmp_path, capsys):
    """The roof's load-deflection through its snap (a case of CURVE_FILES) as CSV and plot; a
    case without a path writes none."""
    assert main(["verify", "roof-snap-through", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    written = sorted(p.suffix for p in tmp_path.iterdir())
    assert written == [".csv", ".png"] and out.count("wrote ") == 2
    assert main(["verify", "stress-free", "--out", str(tmp_path / "plain")]) == 0
    assert "wrote " not in capsys.readouterr().out and not (tmp_path / "plain").exists()


def test_verify_refuses_a_hybrid_case_on_a_laminated_tape(capsys):
    """Refused before anything is built, with the reason; "all" skips those cases instead."""
    from pathlib import Path

    cfrp = str(Path(__file__).parents[1] / "demos" / "cfrp_tape.toml")
    assert main(["verify", "hybrid-cantilever", cfrp]) == 2
    assert "isotropic arc section" in capsys.readouterr().err


SHORT_RUN = (
    "[tape]\nL = 0.1\n[coiling]\nhub_angle = 0.5\n[mesh]\npreset = 'coarse'\n"
    "[deployment]\nt_end = 0.003\nrelease_time = 0.0005\n[output]\nvtx_every = 2\ncheckpoint_every = 2\n"
)

# the same with the hub free to turn (10^-5 kg m^2, some 30 times the short tape's own inertia)
FREE_HUB_RUN = SHORT_RUN.replace("[deployment]\n", "[deployment]\nhub = 'free'\n") + "[hub]\ninertia = 1e-5\n"

# the hybrid's run: the coarse benchmark coiled 4.5 rad (its window leaves the root once) and
# deployed 10 ms, a window move on the way, checkpoints every 3 steps
HYBRID_RUN = (
    "[model]\nkind = 'hybrid'\n[coiling]\nhub_angle = 4.5\n[mesh]\npreset = 'coarse'\n"
    "[deployment]\nt_end = 0.01\n[output]\nvtx_every = 3\ncheckpoint_every = 3\n"
)


def test_run_pipeline_then_deploy_from_its_checkpoint(tmp_path, capsys):
    """tapecoil run (coil, stow, deploy) on a short tape, then tapecoil deploy from its checkpoint."""
    path = tmp_path / "short.toml"
    path.write_text(SHORT_RUN)
    out = tmp_path / "run"
    # stops at t_end before lambda = 1: exit status 1, but every result is written
    assert main(["run", str(path), "--out", str(out), "--json", "--no-report"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["coiling"]["completed"] and not result["completed"]
    deployment = result["deployment"]
    assert deployment["time"] == pytest.approx(0.003) and "t_end" in deployment["message"]
    for name in (
        "summary.json",
        "stowed/meta.json",
        "coiling_history.csv",
        "deployment_history.csv",
        "deployment.bp",
        "deployed/meta.json",
        "snapshots/deployment_cells.npz",
    ):
        assert (out / name).exists(), name
    assert json.loads((out / "summary.json").read_text()) == result
    # the deployment again, from the checkpoint (configuration read beside it)
    again_dir = tmp_path / "again"
    assert main(["deploy", str(out / "stowed"), "--out", str(again_dir), "--json", "--no-report"]) == 1
    again = json.loads(capsys.readouterr().out)["deployment"]
    assert again["lambda"] == pytest.approx(deployment["lambda"], abs=1e-6)
    assert again["measures"]["energy"]["stowed"] == pytest.approx(
        deployment["measures"]["energy"]["stowed"], rel=1e-6
    )


def _tapecoil(*args, **kwargs):
    """The console script in a subprocess (signals reach it as they would from a terminal)."""
    import sys

    return subprocess.Popen([sys.executable, "-m", "tapecoil", *args], **kwargs)


@pytest.mark.parametrize(
    ("phase", "after", "run"),
    [
        # the coiling's restart is also tests/test_coiling.py's, without the signal: make validate
        pytest.param("coiling", 3, SHORT_RUN, marks=pytest.mark.slow),
        ("deployment", 5, SHORT_RUN),
        # the free hub's restart state on top of the fixed hub's: make validate
        pytest.param("deployment", 5, FREE_HUB_RUN, marks=pytest.mark.slow),
        # the hybrid's state beside the full shell's, in both phases (its deployment past the
        # release, whose 20 steps keep no hybrid state)
        pytest.param("coiling", 30, HYBRID_RUN, marks=pytest.mark.slow),
        pytest.param("deployment", 30, HYBRID_RUN, marks=pytest.mark.slow),
    ],
    ids=["coiling", "deployment", "deployment-free-hub", "hybrid-coiling", "hybrid-deployment"],
)
def test_a_stopped_run_resumes_to_the_same_result(tmp_path, phase, after, run):
    """SIGTERM during the coiling or the deployment (with a fixed or a free hub, or the hybrid
    model): the run stops after its step with the checkpoint written (exit 143); --resume
    finishes it with the result of a run never stopped."""
    import signal
    import time

    path = tmp_path / "short.toml"
    path.write_text(run)
    whole, stopped = tmp_path / "whole", tmp_path / "stopped"
    assert (
        _tapecoil(
            "run", str(path), "--out", str(whole), "--no-report", "--json", stdout=subprocess.DEVNULL
        ).wait()
        == 1
    )
    proc = _tapecoil("run", str(path), "--out", str(stopped), "--no-report", "--json", stdout=subprocess.PIPE)
    log = stopped / "run.log"
    marker = f"{phase} {'rad' if phase == 'coiling' else 's'} = "
    deadline = time.monotonic() + 120
    while not (log.is_file() and log.read_text().count(marker) >= after):
        assert proc.poll() is None and time.monotonic() < deadline, "the run ended before it could be stopped"
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM
    summary = json.loads(out)
    assert summary["interrupted"] == "SIGTERM" and not summary["completed"]
    assert (stopped / ("stowed" if phase == "coiling" else "deployed") / "meta.json").is_file()
    assert (
        _tapecoil(
            "run",
            str(path),
            "--out",
            str(stopped),
            "--resume",
            "--no-report",
            "--json",
            stdout=subprocess.DEVNULL,
        ).wait()
        == 1
    )
    a = json.loads((whole / "summary.json").read_text())
    b = json.loads((stopped / "summary.json").read_text())
    for key in ("coiling", "deployment"):
        assert len(a[key]["measures"]) == len(b[key]["measures"])
    for ra, rb in zip(a["validation"], b["validation"], strict=True):
        assert ra["quantity"] == rb["quantity"]
        assert rb["computed"] == pytest.approx(ra["computed"], rel=1e-8, abs=1e-14), ra["quantity"]
    for name in ("coiling_history.csv", "deployment_history.csv"):
        ha = list(csv.DictReader((whole / name).open()))
        hb = list(csv.DictReader((stopped / name).open()))
        assert len(ha) == len(hb), name
        keys = (
            "strain_energy",
            "kinetic_energy",
            "lambda",
            "end_slide",
            "hub_angle",
            "hub_rate",
            "time",
            "step",
        )
        for key in keys:
            if key in ha[0]:
                va = np.array([float(r[key]) for r in ha])
                vb = np.array([float(r[key]) for r in hb])
                assert np.allclose(va, vb, rtol=1e-8, atol=1e-14), (name, key)


HEAVY = ("dolfinx", "petsc4py", "mpi4py", "ufl")


@pytest.mark.parametrize("command", ["theory", "config"])
def test_theory_and_config_do_not_load_dolfinx(command):
    """The commands that compute no finite elements start without DOLFINx, PETSc or MPI."""
    import sys

    code = (
        "import sys\n"
        "from tapecoil.app.cli import main\n"
        f"assert main([{command!r}]) == 0\n"
        f"loaded = sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r}))\n"
        "assert not loaded, loaded\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip()  # the table or the TOML was printed
    # python3 -m tapecoil: -X importtime lists every module imported, on stderr
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "tapecoil", command], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    imported = {line.rsplit("|", 1)[-1].strip().split(".")[0] for line in done.stderr.splitlines()}
    assert "tapecoil" in imported and not imported & set(HEAVY)


def _read_msh(path):
    """Quadrilaterals and physical groups of a .msh file, read by gmsh itself."""
    import gmsh

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        types, tags, _ = gmsh.model.mesh.getElements(2)
        quads = sum(len(t) for ty, t in zip(types, tags, strict=True) if ty == 3)  # 3: 4-node quad
        groups = {gmsh.model.getPhysicalName(d, t) for d, t in gmsh.model.getPhysicalGroups()}
        nodes = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)
    finally:
        gmsh.finalize()
    return quads, groups, nodes


def _check_mesh_files(directory, along, across, comm):
    """The four files of ``tapecoil mesh`` read back: the expected cells, tags and coordinates."""
    import dolfinx.io

    from tapecoil.geometry.meshes import FREE_END, ROOT, SIDE_NEG, SIDE_POS

    cfg, cells = load_config(), along * across
    if comm.rank == 0:
        for name, flat in (("strip-coarse.msh", True), ("strip-coarse-surface.msh", False)):
            quads, groups, nodes = _read_msh(directory / name)
            assert quads == cells, name
            assert groups == {"strip", "root", "free_end", "side_neg", "side_pos"}, name
            # parameter coordinates lie in the plane; the surface's edges rise to R (1 - cos(alpha / 2))
            top = cfg.tape.R * (1 - np.cos(cfg.tape.alpha / 2))
            assert np.max(np.abs(nodes[:, 2])) == pytest.approx(0.0 if flat else top, abs=1e-12), name
    for name, grid, gdim in (("strip-coarse.xdmf", "strip", 2), ("strip-coarse-surface.xdmf", "surface", 3)):
        with dolfinx.io.XDMFFile(comm, str(directory / name), "r") as f:
            mesh = f.read_mesh(name=grid)
            mesh.topology.create_connectivity(1, 2)
            facets = f.read_meshtags(mesh, name="facets")
        assert mesh.geometry.dim == gdim
        assert mesh.topology.index_map(2).size_global == cells
        # each facet counted once, on the rank that owns it
        owned = facets.values[facets.indices < mesh.topology.index_map(1).size_local]
        counts = [comm.allreduce(int(np.sum(owned == tag))) for tag in (ROOT, FREE_END, SIDE_NEG, SIDE_POS)]
        assert counts == [across, across, along, along]


def test_mesh_command_writes_readable_files(tmp_path, capsys):
    """tapecoil mesh --preset coarse: the 0.5 m benchmark tape in 40 x 4 cells, four files."""
    from mpi4py import MPI

    out = tmp_path / "meshes"
    assert main(["mesh", "--preset", "coarse", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "40 x 4 quadrilaterals" in text and "205 nodes, 160 cells" in text
    assert "element size 12.5 mm along the tape, 8.895 mm across" in text
    for name in (
        "strip-coarse.msh",
        "strip-coarse.xdmf",
        "strip-coarse-surface.msh",
        "strip-coarse-surface.xdmf",
    ):
        assert str(out / name) in text
    _check_mesh_files(out, 40, 4, MPI.COMM_WORLD)


def test_mesh_command_takes_the_configuration(tmp_path, capsys):
    """The configured tape and mesh fields are meshed; the default directory is meshes/ here."""
    import os

    path = tmp_path / "short.toml"
    # a hub_angle the 0.1 m tape can coil (at most 7.8 rad): the configuration must be valid
    path.write_text(
        "[tape]\nL = 0.1\n[coiling]\nhub_angle = 0.5\n"
        "[mesh]\npreset = 'coarse'\nelements_across = 3\ngrading = 2.0\n"
    )
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        assert main(["mesh", str(path)]) == 0
    finally:
        os.chdir(cwd)
    text = capsys.readouterr().out
    assert "8 x 3 quadrilaterals" in text and "24 cells" in text
    assert "to" in text.split("element size")[1].split("along")[0]  # graded: first to last length
    assert (tmp_path / "meshes" / "strip-coarse.msh").is_file()


def test_mesh_command_refuses_bad_input_before_meshing(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    assert main(["mesh", "--preset", "coarse", "--out", str(blocker / "meshes")]) == 2
    assert "--out" in capsys.readouterr().err
    path = tmp_path / "bad.toml"
    path.write_text("[mesh]\ngrading = 0.5\n")
    assert main(["mesh", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "mesh.grading" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.mpi
def test_mesh_command_on_two_ranks(tmp_path, capsys):
    """Under MPI rank 0 meshes and writes the .msh; the XDMF files are written together."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = Path(comm.bcast(str(tmp_path), root=0)) / "meshes"
    assert main(["mesh", "--preset", "coarse", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert ("205 nodes, 160 cells" in text) == (comm.rank == 0)  # rank 0 prints
    comm.barrier()
    _check_mesh_files(out, 40, 4, comm)
