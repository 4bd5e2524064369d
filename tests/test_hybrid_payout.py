"""A driven hub's payout with the shell-beam hybrid: its coil turned back, the window following the
lift-off down to the root, side by side with the full shell's payout."""

import dataclasses

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import Config

ANGLE, LAMBDA_END = 6.0, 0.9  # the coarse benchmark tape: the window leaves the root and comes back


def payout_config(kind: str, angle: float = ANGLE, lambda_end: float = LAMBDA_END, **payout) -> Config:
    config = Config()
    return dataclasses.replace(
        config,
        mesh=dataclasses.replace(config.mesh, preset="coarse"),
        coiling=dataclasses.replace(config.coiling, hub_angle=angle),
        payout=dataclasses.replace(config.payout, lambda_end=lambda_end, **payout),
        model=dataclasses.replace(config.model, kind=kind),
        output=dataclasses.replace(config.output, report=False),
    )


@pytest.fixture(scope="module")
def paid_out(tmp_path_factory):
    """The coarse benchmark tape coiled by 6 rad and paid out to lambda = 0.9 through the
    pipeline, by the hybrid and by the full shell (one rank each)."""
    from tapecoil.app.pipeline import run

    out = {}
    for kind in ("hybrid", "shell"):
        directory = tmp_path_factory.mktemp(f"payout_{kind}")
        summary = run(
            payout_config(kind), directory, phases=("coiling", "payout"), comm=MPI.COMM_SELF, progress=False
        )
        out[kind] = directory, summary
    return out


def history(directory) -> dict[str, np.ndarray]:
    from tapecoil.post.plots import read_history

    return read_history(directory / "payout_history.csv")


def at_angles(h: dict, key: str, angles: np.ndarray) -> np.ndarray:
    """A history's column read at the hub ``angles`` (the payout's angles fall)."""
    return np.interp(angles, h["hub_angle"][::-1], h[key][::-1])


@pytest.mark.slow
def test_the_hybrid_pays_out_as_the_full_shell_does(paid_out):
    """Coarse benchmark tape, 6 rad paid out to lambda = 0.9 by each model from its own coil.
    Side by side at the hybrid's hub angles: the strain energy within 0.5 % (measured 0.09 % at
    most; 0.17 % from 9 rad), the coiled length within 1.5 % (0.26 %; 0.6 % from 9 rad), and
    the hub torque read from the root's reactions, over the payout, within 2 % of the full
    shell's (0.23 %). The physics on its own: the hybrid's hub torque is steady coiling's
    rho (T + b w(rho)) within 5 % in the band of lambda it passes (as the full shell's,
    test_payout.py; measured 0.7 %, and 2.1 % from 9 rad)."""
    (hyb_dir, hybrid), (shell_dir, shell) = paid_out["hybrid"], paid_out["shell"]
    for summary in (hybrid, shell):
        assert summary["completed"] and summary["payout"]["completed"]
    a, b = history(hyb_dir), history(shell_dir)
    assert hybrid["payout"]["hub_angle"] == pytest.approx(shell["payout"]["hub_angle"])
    angles = a["hub_angle"]
    energy = at_angles(b, "strain_energy", angles)
    assert np.max(np.abs(a["strain_energy"] / energy - 1)) < 5e-3
    coiled = at_angles(b, "coiled_length", angles)
    assert np.max(np.abs(a["coiled_length"] / coiled - 1)) < 1.5e-2
    assert np.mean(a["hub_torque_reaction"]) == pytest.approx(np.mean(b["hub_torque_reaction"]), rel=0.02)
    torque = hybrid["payout"]["measures"]["hub_torque_vs_steady"]
    assert len(torque["bands"]) >= 1 and torque["max_error"] < 0.05
    assert hybrid["payout"]["run"]["dofs"] < shell["payout"]["run"]["dofs"]


@pytest.mark.slow
def test_the_hybrid_payouts_window_follows_the_lift_off_to_the_root(paid_out):
    """The window moves back as the lift-off runs down the coil: its start falls move by move
    to the root, the flattened beam on the coil becoming shell, and the shell keeps
    ``window_behind`` of the coil behind the lift-off at every step (a consistency check of the
    move rule, read on the hybrid's centre line). The history and the summary say where the
    window was."""
    directory, summary = paid_out["hybrid"]
    config = payout_config("hybrid")
    h = history(directory)
    windows = summary["payout"]["run"]["windows"]
    coiled_windows = summary["coiling"]["run"]["windows"]
    back = windows[len(coiled_windows) :]
    assert len(back) >= 2
    starts = [w[1] for w in back]
    assert all(s1 < s0 for s0, s1 in zip([coiled_windows[-1][1], *starts], starts, strict=False))
    assert np.all(np.diff(h["window_start"]) <= 1e-12) and starts[-1] == 0.0
    assert np.min(h["coiled_length"] - h["window_start"]) >= config.model.window_behind - 1e-9


@pytest.mark.slow
def test_a_payout_alone_starts_from_the_hybrids_stowed_coil(tmp_path, paid_out):
    """``tapecoil payout STOWED`` with the hybrid: the payout from a hybrid coiling's stowed
    checkpoint (the hybrid's state in its tables) is the payout of the run that coiled it, row
    by row to 1e-10; a stowed checkpoint that does not hold the hybrid's coil (the full
    shell's) is refused before anything is computed, with what to do."""
    from tapecoil.app.pipeline import run

    config = payout_config("hybrid")
    stowed = paid_out["hybrid"][0] / "stowed"
    summary = run(
        config, tmp_path / "alone", phases=("payout",), stowed=stowed, comm=MPI.COMM_SELF, progress=False
    )
    assert summary["payout"]["completed"]
    a, b = history(tmp_path / "alone"), history(paid_out["hybrid"][0])
    for key in ("hub_angle", "strain_energy", "hub_torque_reaction", "window_start"):
        np.testing.assert_allclose(a[key], b[key], rtol=1e-10, atol=1e-14, err_msg=key)
    with pytest.raises(ValueError, match=r"not the stowed checkpoint of a completed coiling by the hybrid"):
        run(
            config,
            tmp_path / "refused",
            phases=("payout",),
            stowed=paid_out["shell"][0] / "stowed",
            comm=MPI.COMM_SELF,
            progress=False,
        )
    assert not (tmp_path / "refused" / "payout_history.csv").exists()


@pytest.mark.slow
def test_the_payouts_pull_acts_on_the_hybrid():
    """``payout.tension`` acts: the coarse tape coiled by the hybrid to 6 rad with the coiling's
    pull (1 N), then turned back by 0.5 rad with 1.5 N, carries 1.5 N in its free part: the arc
    beam's axial force beyond the window (read from its strains, not from the load; the free
    part leaves the guide line at a small slope)."""
    from tapecoil.phases.hybrid_coiling import HybridCoiling

    config = payout_config("hybrid", tension=1.5)
    coiling = HybridCoiling(config, MPI.COMM_SELF)
    coiling.flatten()
    coiling.coil(config.coiling.hub_angle)
    coiling.set_pull(config.payout.tension)
    coiling.coil(config.coiling.hub_angle - 0.5)
    assert coiling.pull == 1.5 and coiling.records[-1].hub_angle == pytest.approx(5.5)
    x, N = coiling.hybrid.beam.axial_force()
    free = x[:, 0] > coiling.hybrid.shell.surface.xi_range[0][1] + 0.05
    assert free.sum() > 5
    np.testing.assert_allclose(N[free], 1.5, rtol=0.01)


@pytest.mark.slow
@pytest.mark.mpi
def test_two_ranks_pay_out_the_hybrid_as_one():
    """The coarse tape coiled by the hybrid to 6 rad and paid out to lambda = 0.88 (the window
    moved back on the way), on 2 ranks and on each alone: the same windows' places, the same strain
    energy and hub torque (1e-6) and lift-off (1e-9 of the length)."""
    from tapecoil.phases.hybrid_coiling import HybridCoiling
    from tapecoil.phases.payout import payout_angle

    config = payout_config("hybrid", angle=6.0, lambda_end=0.88)

    def pay_out(comm):
        coiling = HybridCoiling(config, comm)
        coiling.flatten()
        coiling.coil(config.coiling.hub_angle)
        moves = len(coiling.moves)
        coiling.coil(payout_angle(config))
        return coiling, moves

    (parallel, coiled), (serial, _) = pay_out(MPI.COMM_WORLD), pay_out(MPI.COMM_SELF)
    assert MPI.COMM_WORLD.size > 1
    assert len(parallel.moves) > coiled
    assert [m[1:] for m in parallel.moves] == [m[1:] for m in serial.moves]
    assert parallel.strain_energy() == pytest.approx(serial.strain_energy(), rel=1e-6)
    assert parallel.hub_torque() == pytest.approx(serial.hub_torque(), rel=1e-6)
    assert parallel.lift_off() == pytest.approx(serial.lift_off(), abs=1e-9 * config.tape.L)


@pytest.mark.slow
def test_a_stopped_hybrid_payout_goes_on_from_its_checkpoint_as_if_never_stopped(tmp_path, paid_out):
    """The hybrid's payout stopped after 30 steps (between its two moves back) and
    resumed from its checkpoint (paid_out/, the hybrid's tables beside the full shell) ends as
    the uninterrupted payout of the same coil: every row's hub angle, strain energy, hub torque
    and lift-off to 1e-10."""
    from test_hybrid_coiling import StopAfter

    from tapecoil.phases.hybrid_coiling_run import run_hybrid_coiling
    from tapecoil.phases.hybrid_payout import run_hybrid_payout

    config, comm = payout_config("hybrid"), MPI.COMM_SELF
    _, model, coiling = run_hybrid_coiling(config, tmp_path, comm, progress=False)
    stopped = run_hybrid_payout(config, tmp_path, comm, model, coiling, progress=False, stop=StopAfter(30))
    assert stopped["interrupted"] == "SIGTERM" and not stopped["completed"]
    resumed = run_hybrid_payout(config, tmp_path, comm, resume=tmp_path / "paid_out", progress=False)
    assert resumed["completed"]
    a, b = history(tmp_path), history(paid_out["hybrid"][0])
    assert len(a["hub_angle"]) == len(b["hub_angle"])
    for key in ("hub_angle", "strain_energy", "hub_torque_reaction", "coiled_length", "window_start"):
        np.testing.assert_allclose(a[key], b[key], rtol=1e-10, atol=1e-14, err_msg=key)
