"""A driven hub paying the tape out, and the axial force read across the tape's sections."""

import dataclasses
import json

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import CoilingConfig, Config, ConfigError, PayoutConfig, TapeConfig


def short_tape(hub_angle=3.0, L=0.12, lambda_end=0.9) -> Config:
    """The benchmark section on a short tape, coarse mesh: a run of seconds."""
    cfg = Config()
    return dataclasses.replace(
        cfg,
        tape=dataclasses.replace(TapeConfig(), L=L),
        coiling=dataclasses.replace(CoilingConfig(), hub_angle=hub_angle),
        payout=dataclasses.replace(PayoutConfig(), lambda_end=lambda_end),
        mesh=dataclasses.replace(cfg.mesh, preset="coarse"),
    )


def _flattened(comm):
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    model = CoilingProblem(short_tape(), comm)
    CoilingRun(model).flatten()
    return model


def test_axial_force_in_the_free_part_is_the_pull():
    """Flattened onto the hub with the pull T = 1 N: beyond the root's ploy region nothing but the
    pull acts along the tape, so statics asks N = T across every section there. The sections'
    force is read from the strain energy of the cells the cut passes through, which knows nothing
    of the pull (and, at the free end's last cut, equals the end's internal force: a consistency
    check of the reading)."""
    from tapecoil.measures.section_forces import SectionForces

    model = _flattened(MPI.COMM_SELF)
    sections = SectionForces(model.model, model.tape.contact.nodes, MPI.COMM_SELF)()
    pull = model.config.coiling.tension
    free = sections["xi1"] > 0.06
    assert np.abs(sections["axial_force"][free] - pull).max() < 2e-3 * pull
    # the force across the last cut along the guide (+x) is the end's
    assert sections["force"][-1, 0] == pytest.approx(model.edge_forces()["tension"], rel=1e-9)
    # the cuts' tangents point along the tape, towards the free end
    assert np.all(sections["tangent"][free, 0] > 0.99)


@pytest.mark.mpi
def test_two_ranks_read_the_sections_as_one():
    from tapecoil.measures.section_forces import SectionForces

    out = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        model = _flattened(comm)
        out.append(SectionForces(model.model, model.tape.contact.nodes, comm)())
    assert MPI.COMM_WORLD.size > 1
    np.testing.assert_allclose(out[0]["xi1"], out[1]["xi1"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[0]["axial_force"], out[1]["axial_force"], rtol=1e-6, atol=1e-8)


@pytest.fixture(scope="module")
def paid_out(tmp_path_factory):
    """The short tape coiled by 3 rad and paid out to lambda = 0.9 through the pipeline."""
    from tapecoil.app.pipeline import run

    directory = tmp_path_factory.mktemp("payout")
    summary = run(short_tape(), directory, phases=("coiling", "payout"), comm=MPI.COMM_SELF, progress=False)
    return directory, summary


@pytest.mark.slow
def test_payout_turns_the_hub_back_to_the_deployed_fraction(paid_out):
    from tapecoil import theory

    directory, summary = paid_out
    payout, cfg = summary["payout"], short_tape()
    assert summary["completed"] and payout["completed"]
    assert payout["start_hub_angle"] == pytest.approx(3.0)
    assert payout["tension"] == cfg.coiling.tension  # payout.tension = 0: the coiling's pull
    target = theory.rotation_for_coiled_length(0.1 * cfg.tape.L, cfg.hub.radius, cfg.tape.h)
    assert payout["hub_angle"] == pytest.approx(target)
    # lambda read from the contact (the deployment's lift-off) reaches the configured fraction
    assert payout["measures"]["lambda_end"] == pytest.approx(0.9, abs=0.08)
    assert payout["measures"]["lambda_start"] < payout["measures"]["lambda_end"] - 0.1
    rows = (directory / "payout_history.csv").read_text().splitlines()
    header = rows[0].split(",")
    for key in (
        "coiling_tension_outer",
        "eq_4_5",
        "eq_2_6_edges_outer",
        "lambda",
        "steady_torque",
        "hub_torque_reaction",
    ):
        assert key in header
    # the outer turn's law with its free edges' share lies above the plate's, band by band
    m = payout["measures"]
    plate, edges = (
        m["outer_turn_tension_vs_eq_2_6"]["bands"],
        m["outer_turn_tension_vs_eq_2_6_edges"]["bands"],
    )
    assert len(edges) == len(plate) >= 2
    assert all(e["reference"] > p["reference"] for e, p in zip(edges, plate, strict=True))
    angles = [float(r.split(",")[header.index("hub_angle")]) for r in rows[1:]]
    assert np.all(np.diff(angles) < 0)
    assert (directory / "paid_out" / "meta.json").is_file()
    assert json.loads((directory / "summary.json").read_text())["payout"]["completed"]


@pytest.mark.slow
def test_payout_hub_torque_is_steady_coilings(paid_out):
    """The hub torque read from the root's reactions (not from the energy balance) against steady
    coiling rho (T + b w(rho)), the energy balance of a step with rho the outer turn's measured
    radius: paying out frictionless and quasi-static is coiling reversed. Within 5 % in every
    band of lambda (coarse mesh: the per-step value oscillates by about 10 % as nodes pass the
    tangent point, and the bands' means carry it)."""
    measure = paid_out[1]["payout"]["measures"]["hub_torque_vs_steady"]
    assert len(measure["bands"]) >= 2
    assert measure["max_error"] < 0.05


@pytest.mark.slow
def test_payout_figure_is_drawn(paid_out):
    from tapecoil.post.plots import payout_forces

    path = payout_forces(paid_out[0])
    assert path is not None and path.stat().st_size > 10_000


def test_payout_that_deploys_nothing_is_refused_before_computing():
    from tapecoil.phases.payout import check_payout, payout_angle

    cfg = short_tape(lambda_end=0.2)  # 3 rad wound hold 0.04 m of 0.12: lambda 0.67 already
    with pytest.raises(ConfigError, match=r"payout\.lambda_end"):
        check_payout(cfg, 3.0)
    assert payout_angle(short_tape(lambda_end=0.9)) < 3.0
    with pytest.raises(ConfigError, match=r"payout\.lambda_end"):
        short_tape(lambda_end=1.0).check()


def test_payout_keys_act():
    """payout.tension sets the pull held while paying out, payout.max_step the largest step; left
    at 0 they take the coiling's."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun
    from tapecoil.phases.payout import PayoutPhase

    cfg = short_tape(hub_angle=0.3, lambda_end=0.99)
    cfg = dataclasses.replace(cfg, payout=dataclasses.replace(cfg.payout, tension=1.5, max_step=0.05))
    model = CoilingProblem(cfg, MPI.COMM_SELF)
    run = CoilingRun(model)
    run.flatten()
    run.coil(0.3)
    phase = PayoutPhase(model)
    assert phase.pull == 1.5 and phase.run.max_step == 0.05
    phase.advance()
    assert float(model.tension.value) == 1.5
    assert all(abs(r["step"]) <= 0.05 + 1e-12 for r in phase.history)
    assert phase.history[-1]["tension"] == pytest.approx(1.5, rel=1e-6)


@pytest.mark.mpi
def test_two_ranks_pay_out_as_one():
    """The same short payout distributed over the ranks and on each rank alone."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun
    from tapecoil.phases.payout import PayoutPhase

    def pay_out(comm):
        model = CoilingProblem(short_tape(hub_angle=1.0, lambda_end=0.96), comm)
        run = CoilingRun(model)
        run.flatten()
        run.coil(1.0)
        phase = PayoutPhase(model)
        phase.advance()
        return phase.history[-1]

    parallel, serial = pay_out(MPI.COMM_WORLD), pay_out(MPI.COMM_SELF)
    assert MPI.COMM_WORLD.size > 1
    assert parallel["hub_angle"] == serial["hub_angle"]
    for key in ("coiling_tension_outer", "coiling_tension", "hub_torque_reaction", "lambda", "strain_energy"):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-6, abs=1e-9), key


SHORT_PAYOUT = (
    "[tape]\nL = 0.12\n[coiling]\nhub_angle = 2.0\n[mesh]\npreset = 'coarse'\n"
    "[payout]\nlambda_end = 0.95\n[output]\nvtx_every = 2\ncheckpoint_every = 2\nreport = false\n"
)


@pytest.mark.slow
def test_a_stopped_payout_resumes_to_the_same_result(tmp_path):
    """SIGTERM during a payout: it stops after its step with paid_out/ written (exit 143), and
    tapecoil payout --resume finishes it with the history of a payout never stopped."""
    import csv
    import signal
    import subprocess
    import sys
    import time

    from tapecoil.app.cli import main

    path = tmp_path / "short.toml"
    path.write_text(SHORT_PAYOUT)
    coil = tmp_path / "coil"
    assert main(["coil", str(path), "--out", str(coil), "--json", "--no-report"]) == 0
    stowed = str(coil / "stowed")

    def payout(out, *extra, **kw):
        cmd = [sys.executable, "-m", "tapecoil", "payout", stowed, "--out", str(out), "--json", *extra]
        return subprocess.Popen(cmd, **kw)

    whole, stopped = tmp_path / "whole", tmp_path / "stopped"
    assert payout(whole, stdout=subprocess.DEVNULL).wait() == 0
    proc = payout(stopped, stdout=subprocess.PIPE)
    log, deadline = stopped / "run.log", time.monotonic() + 120
    while not (log.is_file() and log.read_text().count("payout rad = ") >= 5):
        assert proc.poll() is None and time.monotonic() < deadline, (
            "the payout ended before it could be stopped"
        )
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM
    assert json.loads(out)["interrupted"] == "SIGTERM"
    assert (stopped / "paid_out" / "meta.json").is_file()
    assert payout(stopped, "--resume", stdout=subprocess.DEVNULL).wait() == 0
    ha = list(csv.DictReader((whole / "payout_history.csv").open()))
    hb = list(csv.DictReader((stopped / "payout_history.csv").open()))
    assert len(ha) == len(hb)
    for ra, rb in zip(ha, hb, strict=True):
        for key in ("hub_angle", "strain_energy", "coiling_tension_outer", "lambda"):
            if ra[key] == "":  # no outer-turn station on a coil this short
                assert rb[key] == "", key
            else:
                assert float(rb[key]) == pytest.approx(float(ra[key]), rel=1e-8, abs=1e-14), key
    a = json.loads((whole / "summary.json").read_text())["payout"]
    b = json.loads((stopped / "summary.json").read_text())["payout"]
    assert b["completed"] and b["start_hub_angle"] == a["start_hub_angle"] == pytest.approx(2.0)
