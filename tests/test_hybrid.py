"""The shell-beam hybrid: the coupled Newton solve, the rigid-section tie, the cantilever."""

import math
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import Config, MeshConfig, load_config
from tapecoil.core.dofs import global_scalar
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.verification.hybrid import (
    CANTILEVER_LENGTH,
    FOLD_WINDOW,
    hybrid_cantilever,
    hybrid_cantilever_problem,
    hybrid_fold,
    tape_hybrid,
)


def coarse():
    return MeshResolution.from_config(MeshConfig(preset="coarse"), CANTILEVER_LENGTH)


def test_hybrid_cantilever_matches_the_full_shell_and_turns_rigidly():
    """Tip deflection within 1 % of the full shell's, penalty converged, a rigid turn stress-free."""
    result = hybrid_cantilever(Config(), coarse())
    failed = [(c.name, c.computed, c.error) for c in result.checks if not c.passed]
    assert not failed, failed
    # the tie is met to far below the deflection (2e-5 m): a consistency check of the penalty
    assert result.info["tie_gap_rms"]["position"] < 1e-9


def test_tie_derivatives_agree_with_finite_differences():
    """The tie energy's gradient and Hessian in the beam end's six dofs, as UFL derives them,
    against central differences of the energy and the gradient (at a bent, turned state)."""
    hybrid, _ = hybrid_cantilever_problem(Config(), coarse(), 0.1)
    coupling = hybrid.tie.coupling
    comm = MPI.COMM_WORLD
    shell_q = hybrid.shell.model.q
    rng = np.random.default_rng(3)
    shell_q.x.array[:] = 1e-4 * rng.standard_normal(len(shell_q.x.array))
    shell_q.x.scatter_forward()
    hybrid.tie.turned.value[:] = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    c0 = np.array([1e-3, -2e-3, 5e-4, 0.2, -0.1, 0.3])
    coupling.c.value[:] = c0
    gradient, hessian = coupling.gradient(), coupling.hessian()
    for i in range(6):
        step = 1e-6
        values = []
        for sign in (1, -1):
            coupling.c.value[:] = c0
            coupling.c.value[i] += sign * step
            values.append((global_scalar(coupling.energy, comm), coupling.gradient()))
        coupling.c.value[:] = c0
        assert (values[0][0] - values[1][0]) / (2 * step) == pytest.approx(gradient[i], rel=1e-6, abs=1e-6)
        column = (values[0][1] - values[1][1]) / (2 * step)
        assert column == pytest.approx(hessian[:, i], rel=1e-5, abs=1e-3 * np.abs(hessian).max())


def test_hybrid_solve_cuts_back_and_keeps_its_last_state():
    """A turn in one step of a whole turn fails; the step is cut back and the run arrives."""
    hybrid, tip = hybrid_cantilever_problem(Config(), coarse(), 0.1)
    hybrid.shell.turn("xi1_min", (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
    hybrid.solve(math.pi / 2, first_step=math.pi / 2, max_step=math.pi / 2)
    assert any(r.cutbacks > 0 for r in hybrid.history)
    expected = np.array([0.0, 0.0, -tip[0]]) + np.array([tip[2], 0.0, 0.0])  # turned by pi/2 about y
    # the shell's polynomial displacement cannot turn the exact arc rigidly: alone, a quarter
    # turn leaves its free edge 2.3e-6 m off, which the beam's lever carries to its tip
    assert np.linalg.norm(hybrid.beam.position(tip) - expected) / CANTILEVER_LENGTH < 1e-4


def test_hybrid_solve_refuses_bad_steps():
    hybrid, _ = hybrid_cantilever_problem(Config(), coarse(), 0.1)
    with pytest.raises(ValueError, match="first_step"):
        hybrid.solve(1.0, first_step=2.0, max_step=2.0)


def test_hybrid_folds_in_its_shell_at_the_fold_moment():
    """The benchmark tape, shell over 0.2 m at the root, beam beyond, its end turned to pi:
    the moment plateau, the fold's radius and flat section as the full shell's (coarse mesh),
    the fold inside the window clear of both its ends."""
    config = Config()
    result = hybrid_fold(config, MeshResolution.from_config(MeshConfig(preset="coarse"), config.tape.L))
    failed = [(c.name, c.computed, c.error) for c in result.checks if not c.passed]
    assert not failed, failed
    start, end = result.info["fold_x_range"]
    assert 0.02 < start < end < FOLD_WINDOW - 0.02


def test_hybrid_refuses_a_laminated_wall():
    """The beam's arc section is isotropic: a laminate is refused before anything is built."""
    config = load_config(Path(__file__).parents[1] / "demos" / "cfrp_tape.toml")
    with pytest.raises(ValueError, match="isotropic"):
        tape_hybrid(config, 4, 0.0125, 0.3, 0.1)


@pytest.mark.mpi
def test_two_ranks_solve_the_hybrid_as_one():
    """The hybrid cantilever on all ranks and on each alone: tip deflections and the turned tip
    to 1e-9."""
    assert MPI.COMM_WORLD.size > 1
    parallel = hybrid_cantilever(Config(), coarse(), comm=MPI.COMM_WORLD)
    serial = hybrid_cantilever(Config(), coarse(), comm=MPI.COMM_SELF)
    for key in ("hybrid", "full_shell"):
        assert parallel.info["tip_deflection"][key] == pytest.approx(
            serial.info["tip_deflection"][key], rel=1e-9
        )
    assert parallel.passed and serial.passed
