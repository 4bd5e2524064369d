"""The stability of a coiling's converged states ([solver] stability, phases/step_stability.py):
each history row's eigenvalues against a dense eigen-decomposition of the same stiffness, the
stowed coil's in the summary, and the key refused where it would not act."""

import dataclasses
import math
import time

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import CoilingConfig, Config, ConfigError, TapeConfig, config_from_dict


def short_coil_with_stability() -> Config:
    """The benchmark section on a 0.12 m tape, coarse mesh, coiled by 1 rad (a run of seconds)."""
    cfg = Config()
    return dataclasses.replace(
        cfg,
        tape=dataclasses.replace(TapeConfig(), L=0.12),
        coiling=dataclasses.replace(CoilingConfig(), hub_angle=1.0),
        mesh=dataclasses.replace(cfg.mesh, preset="coarse"),
        solver=dataclasses.replace(cfg.solver, stability=True),
    )


def dense_spectrum(solver) -> np.ndarray:
    """Every eigenvalue of the solver's assembled Jacobian at its state, the held dofs' rows and
    columns removed (one rank; numpy)."""
    from tapecoil.core.stability import held_rows

    A = solver.compute_jacobian()
    n = A.getSize()[0]
    dense = A.getValues(range(n), range(n))
    free = np.setdiff1d(np.arange(n), held_rows(solver))
    return np.linalg.eigvalsh(0.5 * (dense + dense.T)[np.ix_(free, free)])


def test_coiling_rows_and_summary_carry_the_stability(tmp_path):
    """Every row of a short coiling holds the eigenvalue nearest zero and the count of negative
    eigenvalues; the last row's are those of the whole spectrum of the same stiffness (dense,
    numpy) to 1e-6 (SLEPc's shift-and-invert converges to its default tolerance 1e-8); the
    summary holds the stowed coil's, hub held and free, and the judging's cost."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingPhase
    from tapecoil.phases.step_stability import COLUMNS

    model = CoilingProblem(short_coil_with_stability(), MPI.COMM_SELF)
    phase = CoilingPhase(model)
    t0 = time.perf_counter()
    phase.run.flatten()
    phase.run.coil(1.0)
    history = phase.run.result.history
    assert history and all(all(c in row for c in COLUMNS) for row in history)
    spectrum = dense_spectrum(model.solver)
    nearest = spectrum[np.argmin(np.abs(spectrum))]
    last = history[-1]
    assert last[COLUMNS[0]] == pytest.approx(nearest, rel=1e-6)
    assert last[COLUMNS[1]] == int(np.sum(spectrum < 0))
    phase.history = history
    phase.finish(tmp_path)
    stability = phase.summary(None, t0)["stability"]
    assert stability["eigenvalues_hub_held"][0] == pytest.approx(nearest, rel=1e-6)
    assert stability["stable_hub_held"] == (last[COLUMNS[1]] == 0)
    assert stability["states_judged"] == len(history)
    assert math.isfinite(stability["hub_torque_rate"]) and stability["wall_time"] > 0
    assert stability["stable_hub_free"] == (stability["stable_hub_held"] and stability["hub_torque_rate"] > 0)


def test_a_payouts_rows_carry_the_stability():
    """A payout turns the hub back through the coiling's rows: the hub of the short coil turned
    back by half a radian, each of its rows judged, the last against the dense spectrum."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun
    from tapecoil.phases.step_stability import COLUMNS

    model = CoilingProblem(short_coil_with_stability(), MPI.COMM_SELF)
    run = CoilingRun(model)
    run.flatten()
    run.coil(1.0)
    coiled = len(run.result.history)
    run.coil(0.5, start_angle=model.root.angle)
    back = run.result.history[coiled:]
    assert back and float(back[-1]["hub_angle"]) == pytest.approx(0.5)
    assert all(math.isfinite(row[COLUMNS[0]]) for row in back)
    spectrum = dense_spectrum(model.solver)
    assert back[-1][COLUMNS[0]] == pytest.approx(spectrum[np.argmin(np.abs(spectrum))], rel=1e-6)


def test_stability_key_is_typed_and_refused_on_the_hybrid():
    assert config_from_dict({"solver": {"stability": True}}).solver.stability is True
    assert Config().solver.stability is False
    with pytest.raises(ConfigError, match=r"solver\.stability"):
        config_from_dict({"solver": {"stability": "yes"}})
    with pytest.raises(ConfigError, match=r"solver\.stability = true judges the shell model"):
        config_from_dict({"model": {"kind": "hybrid"}, "solver": {"stability": True}})
