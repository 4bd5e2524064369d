"""The hybrid's coiling: a shell window that follows the lift-off, beams before and after it."""

import dataclasses
import math

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import Config, ConfigError, config_from_dict
from tapecoil.phases.hybrid_coiling import HybridCoiling, WindowSettings
from tapecoil.phases.hybrid_line import winding_along
from tapecoil.verification import not_applicable
from tapecoil.verification.hybrid_coil import hybrid_coil


def coarse(angle: float) -> Config:
    config = Config()
    return dataclasses.replace(
        config,
        mesh=dataclasses.replace(config.mesh, preset="coarse"),
        coiling=dataclasses.replace(config.coiling, hub_angle=angle),
    )


# the coarse tapes coiled by the hybrid, shared by the tests that read the same coil or deploy
# from it (a deployment builds its own hybrid from the coiling's and leaves that as it was)
_COILED: dict = {}


def coiled(comm, angle: float) -> HybridCoiling:
    """The coarse tape coiled by the hybrid to ``angle`` [rad] on ``comm`` (collective; computed
    once per process and communicator size)."""
    key = (comm.size, angle)
    if key not in _COILED:
        run = HybridCoiling(coarse(angle), comm)
        run.flatten()
        run.coil(angle)
        _COILED[key] = run
    return _COILED[key]


@pytest.mark.slow
def test_the_hybrid_coils_the_benchmark_as_the_full_shell_does():
    """``hybrid-coil`` (coarse, 5 rad, the window moved off the root once): the strain energy
    within 0.5 % of the full shell's (measured 0.057 %), the coiled length within 0.5 % (0.078 %),
    the free part's height within 0.1 mm (0.051 mm; 0.55 mm with the end's pitch held)."""
    result = hybrid_coil(Config(), "coarse")
    failed = [(c.name, c.computed, c.error) for c in result.checks if not c.passed]
    assert not failed, failed
    windows = result.info["windows"]
    assert len(windows) == 2 and windows[1][1] > 0.0  # it left the root


def test_the_hybrid_coil_lands_on_the_stops():
    """Coiled to 1 rad with stops at 0.3 and 0.7 rad: converged steps end on both, to rounding."""
    run = HybridCoiling(coarse(1.0))
    run.flatten()
    run.coil(1.0, stops=(0.3, 0.7))
    angles = [r.hub_angle for r in run.records]
    for stop in (0.3, 0.7, 1.0):
        assert min(abs(a - stop) for a in angles) < 1e-12, (stop, angles)


def test_the_tensions_compare_at_the_same_hub_angles():
    """Two readings of one swinging tension, offset by 0.01 N: their means over each one's own
    steps differ by more than the offset (here with the wrong sign); read also at common stops,
    the paired comparison there gives the offset to rounding, with a zero standard error."""
    from tapecoil.verification.hybrid_coil import _band_mean, paired_tension, tension_stops

    stops = tension_stops(9.2, 0.5)
    assert stops == pytest.approx([6.0, 6.5, 7.0, 7.5, 8.0, 8.5, 9.0, 9.2])

    def swing(a):
        return 0.4 + 0.1 * np.sin(7.3 * a)

    full_steps, hybrid_steps = np.linspace(6.0, 9.2, 5), np.linspace(6.0, 9.2, 7)
    own = _band_mean([(a, swing(a) - 0.01) for a in hybrid_steps], 6.0) - _band_mean(
        [(a, swing(a)) for a in full_steps], 6.0
    )
    assert abs(own + 0.01) > 0.01
    full = [(a, swing(a)) for a in sorted({*full_steps, *stops})]
    hybrid = [(a, swing(a) - 0.01) for a in sorted({*hybrid_steps, *stops})]
    paired = paired_tension(hybrid, full, stops)
    assert paired["stops"] == len(stops)
    assert paired["difference"] == pytest.approx(-0.01, abs=1e-14)
    assert paired["standard_error"] == pytest.approx(0.0, abs=1e-14)
    assert paired_tension(hybrid, full, ()) is None
    with pytest.raises(RuntimeError, match=r"6\.25 rad"):
        paired_tension(hybrid, full, (6.25,))
    with pytest.raises(ValueError, match="positive"):
        tension_stops(9.2, 0.0)


def test_winding_angles_unwrap_along_the_tape_from_the_root():
    """Points wound 1.5 turns onto a hub and then straight on: their winding angles, read from
    their polar angles alone, climb from 0 at the root through 3 pi without a jump."""
    from tapecoil.hub.frame import HubFrame

    frame = HubFrame(0.0127, 1e-4)
    angle = 3 * math.pi
    psi = np.linspace(0.0, angle, 60)
    # a point wound by psi sits at the hub angle less psi, turned about the axis from the root
    points = np.array([frame.turn_points(np.zeros((3, 1)), angle - p)[:, 0] for p in psi])
    # the free part leaves the coil along the guide, +x, from the top of the hub
    straight = points[-1] + np.outer(np.linspace(0.01, 0.1, 10), [1.0, 0.0, 0.0])
    read = winding_along(frame, angle, np.vstack([points, straight]))
    assert read[:60] == pytest.approx(psi, abs=1e-9)
    assert np.all(np.diff(read[60:]) > 0) and read[-1] < angle + math.pi / 2


def test_bad_hybrid_coilings_are_refused_before_anything_is_built():
    config = coarse(5.0)
    equal = dataclasses.replace(config, coiling=dataclasses.replace(config.coiling, sense="equal"))
    with pytest.raises(ValueError, match=r"coiling\.sense"):
        HybridCoiling(equal)
    with pytest.raises(ValueError, match="shorter than the tape"):
        HybridCoiling(config, window=dataclasses.replace(WindowSettings.from_config(config.model), ahead=0.6))
    assert "opposite sense" in not_applicable("hybrid-coil", equal)


@pytest.mark.slow
@pytest.mark.mpi
def test_two_ranks_coil_the_hybrid_as_one():
    """The hybrid coiled on 2 ranks and on each alone past its first window move: the same
    windows, the same energy (1e-9) and lift-off (1e-9 of the length); carried into the full
    shell and settled there (a hybrid run's stowed state), the same energy (1e-9)."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.hybrid_coiling_run import settle

    assert MPI.COMM_WORLD.size > 1
    runs = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        run = coiled(comm, 4.5)
        shell = CoilingProblem(coarse(4.5), comm)
        run.carry_into(shell)
        settled = settle(shell, run.angle)["strain_energy_settled"]
        runs.append((run.strain_energy(), run.lift_off(), run.moves, settled))
    (e2, s2, m2, settled2), (e1, s1, m1, settled1) = runs
    assert m2 == m1 and len(m1) == 2
    assert e2 == pytest.approx(e1, rel=1e-9)
    assert settled2 == pytest.approx(settled1, rel=1e-9)
    assert abs(s2 - s1) < 1e-9 * 0.5


def test_a_settling_whose_solve_fails_is_tried_again_from_the_carried_state():
    """The full shell settled from a carried state (here the coarse tape pushed off its unloaded
    equilibrium) whose first solve fails: the second attempt starts from the carried state again
    and settles where a settling without the failure does; failing twice, the coiling stops with
    the carried state put back."""
    from tapecoil.core.newton import SolveResult
    from tapecoil.core.stepping import ContinuationError
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.hybrid_coiling_run import settle

    shell = CoilingProblem(coarse(1.0), MPI.COMM_WORLD)
    shell.set_flattening(0.0)
    rng = np.random.default_rng(0)
    carried = shell.model.q.x.array + 1e-6 * rng.standard_normal(shell.model.q.x.array.shape)

    def carry():
        shell.model.q.x.array[:] = carried
        shell.model.q.x.scatter_forward()

    carry()
    clean = settle(shell, 0.0)
    assert clean["attempts"] == 1 and clean["newton_iterations"] > 0
    settled = shell.model.q.x.array.copy()

    solve, calls = shell.solver.solve, []

    def failing(times):
        def attempt():
            calls.append(shell.model.q.x.array.copy())
            if len(calls) <= times:
                shell.model.q.x.array[:] += 1e-3  # a failed solve leaves its last iterate
                return SolveResult(False, 1, -3, 1.0)
            return solve()

        return attempt

    carry()
    shell.solver.solve = failing(1)
    retried = settle(shell, 0.0)
    assert retried["attempts"] == 2 and len(calls) == 2
    assert np.array_equal(calls[1], carried)  # the second attempt started from the carried state
    assert np.allclose(shell.model.q.x.array, settled, rtol=0, atol=1e-12)
    assert retried["strain_energy_settled"] == pytest.approx(clean["strain_energy_settled"], rel=1e-12)

    carry()
    calls.clear()
    shell.solver.solve = failing(2)
    with pytest.raises(ContinuationError, match="2 attempts"):
        settle(shell, 0.0)
    assert np.array_equal(shell.model.q.x.array, carried)


def test_a_hybrid_run_refuses_a_coil_its_window_never_leaves(tmp_path):
    """The coarse tape coiled 2 rad (0.026 m of coil at most) and deployed by the hybrid: its
    window would never leave the root and hold the whole tape at release, so the run is refused
    before anything is computed, naming the keys; coiling alone runs. 4.5 rad passes the check
    (the window leaves the root at 4.5 rad: the run test below)."""
    from tapecoil.app.pipeline import run
    from tapecoil.config import ConfigError
    from tapecoil.config.model import hybrid_deployment_need

    config = coarse(2.0)
    config = dataclasses.replace(config, model=dataclasses.replace(config.model, kind="hybrid"))
    with pytest.raises(
        ConfigError, match=r"coiling.hub_angle = 2 rad .* model.window_behind \+ model.window_move"
    ):
        run(config, tmp_path / "run", progress=False)
    assert not (tmp_path / "run").exists()
    assert hybrid_deployment_need(dataclasses.replace(config, coiling=coarse(4.5).coiling)) is None
    assert hybrid_deployment_need(coarse(2.0)) is None  # the shell model deploys any coil


@pytest.mark.slow
def test_a_run_with_the_hybrid_model_coils_and_deploys_with_the_hybrid(tmp_path):
    """A run with ``model.kind = "hybrid"`` (coarse, 4.5 rad: the window leaves the root once;
    2 ms of deployment): the coiling's summary names its measures as the shell's does, the
    hybrid's own strain energy is within 0.5 % of the settled full shell's (measured 0.05 % at 5
    rad), the stowed checkpoint is the settled full shell's and deploys, a resumed run
    returns the completed coiling's summary without coiling again, the report draws the
    hybrid's history (the root's loads on the hub among it) and says how the stowed state was
    made, and a deployment alone from the stowed checkpoint (the hybrid's coil in its tables)
    is the run's, row by row."""
    import json

    from tapecoil.app.pipeline import run
    from tapecoil.core.checkpoint import read_meta
    from tapecoil.post.plots import read_history

    config = coarse(4.5)
    config = dataclasses.replace(
        config,
        model=dataclasses.replace(config.model, kind="hybrid"),
        deployment=dataclasses.replace(config.deployment, t_end=2e-3, dt=2e-4),
        output=dataclasses.replace(config.output, report=False),
    )
    out = tmp_path / "run"
    summary = run(config, out, progress=False)
    coiling = summary["coiling"]
    assert coiling["completed"] and coiling["hub_angle"] == pytest.approx(4.5)
    measures, figures = coiling["measures"], coiling["run"]
    for name in ("stored_energy_coiled", "strain_energy_total", "outer_radius", "curvature_longitudinal"):
        assert measures[name]["computed"] is not None, name
    settled = measures["strain_energy_total"]["computed"]
    assert figures["model"] == "hybrid" and figures["settling"]["strain_energy_settled"] == pytest.approx(
        settled
    )
    assert measures["hybrid"]["strain_energy"] == pytest.approx(settled, rel=5e-3)
    assert figures["dofs"] < figures["full_shell_dofs"]
    assert len(figures["windows"]) == 2 and figures["windows"][1][1] > 0.0
    history = read_history(out / "coiling_history.csv")
    assert history["window_start"][-1] > 0.0 and np.all(np.isfinite(history["strain_energy"]))
    meta = read_meta(out / "stowed")
    assert meta["completed"] and meta["run"]["model"] == "hybrid"
    deployment = summary["deployment"]
    assert deployment["time"] == pytest.approx(2e-3) and deployment["run"]["model"] == "hybrid"
    assert deployment["run"]["dofs"] < figures["full_shell_dofs"]
    history = read_history(out / "deployment_history.csv")
    for column in (
        "lambda",
        "strain_energy",
        "contact_energy",
        "kinetic_energy",
        "dissipated_energy",
        "root_torque",
    ):
        assert np.all(np.isfinite(history[column])), column
    assert deployment["root_torque_peak"]["value"] >= abs(history["root_torque"][0]) > 0.0
    # the release: the tape starts to move, its energy turned into motion, not made
    assert history["kinetic_energy"][-1] > 0.0
    assert history["strain_energy"][-1] < history["strain_energy"][0]
    assert abs(history["dissipated_energy"][-1]) < 1e-2 * history["strain_energy"][0]
    assert (out / "snapshots").is_dir() and read_meta(out / "deployed")["run"]["model"] == "hybrid"

    if MPI.COMM_WORLD.rank == 0:  # the report's figures from the hybrid's history, and its note
        from tapecoil.post.report import write_report

        page = write_report(out, pictures=False).read_text()
        assert "coiling (hybrid)" in page and "settled there in" in page
        assert "deployment (hybrid)" in page and "Deployed by the hybrid" in page
        assert (out / "figures" / "deployment_energies.png").is_file()
        assert (out / "figures" / "deployment_root_loads.png").is_file()
        assert (out / "figures" / "coiling_forces.png").is_file()

    again = run(config, out, phases=("coiling",), resume=True, progress=False)
    assert again["coiling"]["measures"]["strain_energy_total"]["computed"] == pytest.approx(
        settled, rel=1e-12
    )
    assert again["coiling"]["run"]["steps"] == figures["steps"]
    # a completed hybrid deployment is not recomputed either
    resumed = run(config, out, resume=True, progress=False)
    assert resumed["deployment"]["run"]["steps"] == deployment["run"]["steps"]
    assert resumed["deployment"]["measures"]["lambda0"] == deployment["measures"]["lambda0"]
    assert json.loads((out / "summary.json").read_text())["coiling"]["run"]["model"] == "hybrid"
    # a deployment alone from the hybrid's stowed coil (tapecoil deploy STOWED) is the run's
    alone = tmp_path / "alone"
    deployed_alone = run(config, alone, phases=("deployment",), stowed=out / "stowed", progress=False)
    assert deployed_alone["deployment"]["time"] == pytest.approx(2e-3)
    a, b = read_history(alone / "deployment_history.csv"), read_history(out / "deployment_history.csv")
    for column in ("time", "lambda", "strain_energy", "kinetic_energy", "window_start"):
        np.testing.assert_allclose(a[column], b[column], rtol=1e-9, atol=1e-14, err_msg=column)


def test_the_beam_contact_key_reaches_the_window_settings():
    """[model] beam_contact reaches the coiling's window settings, which the hybrid's beam reads
    when it is built (the contact across the width: tests/test_beam.py), and a value that is
    neither "line" nor "width" is refused."""
    config = config_from_dict({"model": {"kind": "hybrid", "beam_contact": "line"}})
    assert WindowSettings.from_config(config.model).beam_contact == "line"
    assert WindowSettings.from_config(Config().model).beam_contact == "width"
    with pytest.raises(ConfigError, match="beam_contact"):
        config_from_dict({"model": {"kind": "hybrid", "beam_contact": "edges"}})


class StopAfter:
    """A stop request after ``rows`` converged steps, as a signal would make it (the runner's
    :class:`~tapecoil.core.interrupt.StopSignals` check)."""

    def __init__(self, rows: int):
        self.rows, self.seen = rows, 0

    def check(self, comm=None) -> None:
        import signal

        from tapecoil.core.interrupt import Interrupted

        self.seen += 1
        if self.seen >= self.rows:
            raise Interrupted(signal.SIGTERM)


def hybrid_run_config(angle: float) -> Config:
    config = coarse(angle)
    return dataclasses.replace(
        config,
        model=dataclasses.replace(config.model, kind="hybrid"),
        output=dataclasses.replace(config.output, report=False, checkpoint_every=7),
    )


@pytest.mark.slow
def test_a_stopped_hybrid_coiling_goes_on_from_its_checkpoint_as_if_never_stopped(tmp_path):
    """The coarse tape's coiling to 4.5 rad by the hybrid in a run, stopped after 60 steps (past
    the window's move off the root at 3.9 rad, in the middle of a leg between moves) and resumed
    from its checkpoint: every step is the uninterrupted coiling's to 1e-12 (hub angle, step,
    window, lift-off, strain energy, Newton iterations: the state restored is the state left),
    and the history has a row for each. A completed coiling's checkpoint gives back the hybrid's
    own coil (which the deployment starts from) without coiling again."""
    import csv

    from tapecoil.core.checkpoint import read_meta, read_tables
    from tapecoil.phases.hybrid_coiling_run import run_hybrid_coiling

    config = hybrid_run_config(4.5)
    comm = MPI.COMM_WORLD
    stopped, _, _ = run_hybrid_coiling(config, tmp_path, comm, progress=False, stop=StopAfter(60))
    assert stopped["interrupted"] == "SIGTERM" and not stopped["completed"]
    checkpoint = tmp_path / "stowed"
    assert read_meta(checkpoint)["run"]["coiling"]["leg"] is not None and read_tables(checkpoint)
    resumed, _, coil = run_hybrid_coiling(config, tmp_path, comm, resume=checkpoint, progress=False)
    direct = coiled(comm, 4.5)  # the same coiling, never stopped
    assert resumed["completed"] and coil.moves == direct.moves and len(coil.moves) == 2
    assert len(coil.records) == len(direct.records)
    for mine, theirs in zip(coil.records, direct.records, strict=True):
        for key in ("hub_angle", "step", "lift_off", "strain_energy", "iterations"):
            assert getattr(mine, key) == pytest.approx(getattr(theirs, key), rel=1e-12), key
        assert mine.window == theirs.window
    rows = list(csv.DictReader((tmp_path / "coiling_history.csv").open()))
    assert len(rows) == len(direct.records) + 1  # and the flattening's
    assert [float(r["hub_angle"]) for r in rows[1:]] == pytest.approx([r.hub_angle for r in direct.records])

    _, _, again = run_hybrid_coiling(config, tmp_path, comm, resume=checkpoint, progress=False)
    assert again is not None and again.angle == pytest.approx(4.5)
    assert again.strain_energy() == pytest.approx(direct.strain_energy(), rel=1e-12)


@pytest.mark.mpi
def test_a_hybrid_coiling_stopped_on_two_ranks_goes_on_on_one(tmp_path):
    """The coarse tape's hybrid coiling stopped on 2 ranks after 60 steps and resumed from that
    checkpoint on each rank alone ends where the uninterrupted 2-rank coiling does: the same
    windows, the same strain energy and lift-off (1e-9, as 2 ranks against 1 above)."""
    import shutil
    from pathlib import Path

    from tapecoil.phases.hybrid_coiling_run import run_hybrid_coiling

    world = MPI.COMM_WORLD
    config = hybrid_run_config(4.5)
    shared = Path(world.bcast(str(tmp_path), root=0)) / "run"
    run_hybrid_coiling(config, shared, world, progress=False, stop=StopAfter(60))
    own = tmp_path / f"rank{world.rank}"
    shutil.copytree(shared / "stowed", own / "stowed")
    resumed, _, coil = run_hybrid_coiling(config, own, MPI.COMM_SELF, resume=own / "stowed", progress=False)
    direct = coiled(world, 4.5)
    assert resumed["completed"] and coil.moves == direct.moves
    assert coil.strain_energy() == pytest.approx(direct.strain_energy(), rel=1e-9)
    assert abs(coil.lift_off() - direct.lift_off()) < 1e-9 * 0.5
