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
    cantilever_tip_deflection,
    hybrid_cantilever,
    hybrid_cantilever_problem,
    hybrid_fold,
    tape_hybrid,
)


def coarse():
    return MeshResolution.from_config(MeshConfig(preset="coarse"), CANTILEVER_LENGTH)


@pytest.mark.slow
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


@pytest.mark.slow
def test_hybrid_folds_in_its_shell_at_the_fold_moment():
    """The benchmark tape, shell over 0.3 m at the root, beam beyond, its end turned to pi:
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


def carried_and_direct(comm=MPI.COMM_WORLD, load=2.0, force=False, direct=True):
    """A hybrid with 0.1 m of shell stepped to ``load`` (the clamp's turn [rad], or a tip force
    [N] with ``force``), carried over to 0.15 m of shell and stepped on by 5 %; and, with
    ``direct``, the uninterrupted run with 0.15 m. Returns (carried, uninterrupted or None, tip,
    energies at the carry-over)."""
    from tapecoil.models.window import carry_over

    def build(window, name):
        hybrid, tip = hybrid_cantilever_problem(Config(), coarse(), window, comm=comm, name=name)
        if force:
            hybrid.shell.clamp("xi1_min")
            hybrid.beam.end_load(tip, force=(0.0, 0.0, 1.0))
        else:
            hybrid.shell.turn("xi1_min", (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
        return hybrid, tip

    steps = {"first_step": load / 8, "max_step": load / 8}
    old, tip = build(0.1, "old")
    old.solve(load, **steps)
    carried, _ = build(0.15, "carried")
    before = old.energy()
    carry_over(old, carried)
    after = carried.energy()
    carried.solve(1.05 * load, first_step=0.05 * load, max_step=0.05 * load)
    if not direct:
        return carried, None, tip, (before, after)
    uninterrupted, _ = build(0.15, "direct")
    uninterrupted.solve(1.05 * load, **steps)
    return carried, uninterrupted, tip, (before, after)


def test_a_carried_over_state_reaches_the_uninterrupted_runs_equilibrium():
    """The window grown from 0.1 to 0.15 m into the beam at a turn of 2 rad (the sections turned
    rigidly, as the straight part ahead of a ploy region) and under a tip force: one step on,
    tip and energy as the run that had 0.15 m of shell all along (1e-9 of L; 1e-6)."""
    for force, load in ((False, 2.0), (True, 0.5)):
        carried, direct, tip, _ = carried_and_direct(force=force, load=load)
        gap = np.linalg.norm(carried.beam.position(tip) - direct.beam.position(tip))
        assert gap / CANTILEVER_LENGTH < 1e-9, force
        # to the Newton tolerance: 4e-8 under the force
        assert carried.energy() == pytest.approx(direct.energy(), rel=1e-6), force


def test_carry_over_places_the_sections_where_the_beam_had_them():
    """At the carry-over the new shell's nodes are where the old beam's sections put them: after
    a rigid turn by 2 rad, the mean of the tied edge's positions less the turned reference, to
    the shell's own rigid-turn error (2e-6 m at its old edge on this mesh)."""
    import ufl

    from tapecoil.core.rotation import rotation_matrix
    from tapecoil.models.window import carry_over

    old, tip = hybrid_cantilever_problem(Config(), coarse(), 0.1, name="old")
    old.shell.turn("xi1_min", (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
    old.solve(2.0, first_step=0.25, max_step=0.25)
    new, _ = hybrid_cantilever_problem(Config(), coarse(), 0.15, name="new")
    new.shell.turn("xi1_min", (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
    carry_over(old, new)
    R = ufl.as_matrix(rotation_matrix(np.array([0.0, 1.0, 0.0]), 2.0).tolist())
    model = new.shell.model
    assert np.linalg.norm(new.shell.edge_average("xi1_max", model.phi - R * model.phi0)) < 1e-5
    assert np.allclose(new.beam.position(tip), old.beam.position(tip), rtol=0, atol=1e-12)


def test_carry_over_refuses_windows_that_do_not_fit():
    from tapecoil.models.window import carry_over

    old, _ = hybrid_cantilever_problem(Config(), coarse(), 0.15, name="old")
    shorter, _ = hybrid_cantilever_problem(Config(), coarse(), 0.1, name="shorter")
    with pytest.raises(ValueError, match="shorter than the old"):
        carry_over(old, shorter)
    config = Config()
    misplaced, _ = tape_hybrid(config, 4, 0.3 / 23, 0.3, 0.3 / 23 * 13, name="misplaced")
    with pytest.raises(ValueError, match="do not lie where"):
        carry_over(old, misplaced)


@pytest.mark.mpi
def test_two_ranks_solve_the_hybrid_as_one():
    """The hybrid cantilever on all ranks and on each alone: the tip deflection to 1e-9, and a
    carried-over state's tip and energies."""
    assert MPI.COMM_WORLD.size > 1
    parallel, _, _ = cantilever_tip_deflection(Config(), coarse(), comm=MPI.COMM_WORLD)
    serial, _, _ = cantilever_tip_deflection(Config(), coarse(), comm=MPI.COMM_SELF)
    assert parallel == pytest.approx(serial, rel=1e-9)
    # the carry-over gathers both states from every rank
    carried_parallel, _, tip, energies_parallel = carried_and_direct(MPI.COMM_WORLD, direct=False)
    carried_serial, _, _, energies_serial = carried_and_direct(MPI.COMM_SELF, direct=False)
    assert energies_parallel == pytest.approx(energies_serial, rel=1e-9)
    gap = carried_parallel.beam.position(tip) - carried_serial.beam.position(tip)
    assert np.linalg.norm(gap) / CANTILEVER_LENGTH < 1e-9
