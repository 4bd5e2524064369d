"""The shell core against its references (coarse meshes; the full set runs in make validate)."""

import math

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import load_config
from tapecoil.geometry.meshes import FREE_END, MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.shell import NaghdiShell, ShellMaterial, angles_from_director
from tapecoil.verification.cases import run_case
from tapecoil.verification.sze import ROLLUP_MESHES, rollup, semicylinder, slit_plate


def assert_passed(result):
    failed = [(c.name, c.computed, c.reference, c.error) for c in result.checks if not c.passed]
    assert not failed, failed


def test_stress_free_reference():
    assert_passed(run_case("stress-free", load_config(), "coarse"))


def test_tape_linear_coarse():
    result = run_case("tape-linear", load_config(), "coarse")
    assert_passed(result)
    # membrane action carries the beam bending of the curved section
    assert result.info["energy_split"]["membrane"] > 0.99


def test_full_integration_locks_where_psri_does_not():
    from tapecoil.verification.tape import tape_linear

    cfg, res = load_config(), MeshResolution(4, 40)
    full = tape_linear(cfg, res, technology="full").checks[1].computed
    psri = tape_linear(cfg, res, technology="psri").checks[1].computed
    assert full < 0.9 < 0.99 < psri < 1.02


@pytest.mark.parametrize(
    "surface, element_area",
    [
        # a tape's map keeps lengths (sqrt(det a0) = 1): h_e^2 = l1 l2, here 10 mm x b/4
        (StripGeometry(0.0151, 0.0356, 0.1), 0.01 * 0.0356 / 4),
        # a quarter cylinder of radius 2 in (length, angle): sqrt(det a0) = 2
        ("quarter cylinder", 2 * (0.1 / 10) * (math.pi / 2 / 4)),
    ],
)
def test_the_psri_split_uses_the_elements_area_on_the_mid_surface(surface, element_area):
    """The membrane and shear energies' fully integrated fraction is min(h^2 / h_e^2, 1), h_e^2
    the element's area on the 3D mid-surface (its parameter area times sqrt(det a0))."""
    import dolfinx
    import ufl

    from tapecoil.geometry.surfaces import MappedSurface

    if surface == "quarter cylinder":
        surface = MappedSurface(
            lambda xi, ops: (2 * ops.cos(xi[1]), xi[0], 2 * ops.sin(xi[1])), ((0.0, 0.1), (0.0, math.pi / 2))
        )
    h = 1e-4
    strip = create_strip_mesh(MPI.COMM_WORLD, surface, MeshResolution(across=4, along=10))
    shell = NaghdiShell(strip, ShellMaterial(1e9, 0.3, h))
    (a0, a1), (b0, b1) = surface.xi_range
    mean = MPI.COMM_WORLD.allreduce(
        dolfinx.fem.assemble_scalar(dolfinx.fem.form(shell.quadrature.alpha * ufl.dx(domain=strip.mesh)))
    ) / ((a1 - a0) * (b1 - b0))
    assert mean == pytest.approx(h**2 / element_area, rel=1e-10)


def test_rollup_two_turns_coarse():
    result = rollup(ROLLUP_MESHES["coarse"], turns=2)
    assert_passed(result)
    assert len(result.checks) == 4  # half, one, one and a half and two turns


def test_angles_round_trip():
    """angles_from_director inverts the director map, continuing theta_1 through many turns."""
    geom = StripGeometry(0.0151, 0.0356, 0.5)
    xi = np.array([[0.1, 0.2, 0.3], [-0.015, 0.0, 0.012]])
    frame = geom.frame(xi)
    theta = np.array([[0.3, -0.7, 1.1], [13.0, -0.2, 7.5]])
    c0, s0 = np.cos(theta[0]), np.sin(theta[0])
    d = c0 * np.sin(theta[1]) * frame[0] - s0 * frame[1] + c0 * np.cos(theta[1]) * frame[2]
    back = angles_from_director(d, frame, theta1_near=theta[1] + 0.5)
    assert np.allclose(back, theta, atol=1e-12)


def test_edge_motion_is_rigid():
    """A rotated edge: displacement and director of the reference edge turned together."""
    from tapecoil.core.rotation import rotation_matrix
    from tapecoil.models.edges import EdgeMotion

    cfg = load_config()
    strip = create_strip_mesh(MPI.COMM_WORLD, StripGeometry.from_config(cfg), MeshResolution(4, 10))
    model = NaghdiShell(strip, ShellMaterial(cfg.tape.E, cfg.tape.nu, cfg.tape.h))
    axis_point = np.array([cfg.tape.L, 0.0, -0.02])
    end = EdgeMotion(model, FREE_END, axis=np.array([0.0, 1.0, 0.0]), axis_point=axis_point)
    angle = 2 * math.pi + 0.8  # more than a turn: theta_1 continues past 2 pi
    end.set(angle, translation=(0.001, 0.0, 0.0))
    Q = rotation_matrix([0, 1, 0], angle)
    u_space = end.values[0].function_space
    xi = u_space.tabulate_dof_coordinates()[:, :2].T
    on_edge = np.isclose(xi[0], cfg.tape.L)
    X = strip.geometry.phi0(xi[:, on_edge])
    expected = Q @ (X - axis_point[:, None]) + axis_point[:, None] + np.array([[0.001], [0], [0]]) - X
    u = end.values[0].x.array.reshape(-1, 3)[on_edge].T
    assert np.allclose(u, expected, atol=1e-14)
    theta = end.values[1].x.array.reshape(-1, 2)[
        np.isclose(end.values[1].function_space.tabulate_dof_coordinates()[:, 0], cfg.tape.L)
    ]
    assert np.all(theta[:, 1] > 2 * math.pi)  # the unbounded angle, not wrapped


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["default", "fine"])
def test_rollup_refined(preset):
    assert_passed(rollup(ROLLUP_MESHES[preset], turns=2))


@pytest.mark.slow
def test_semicylinder():
    assert_passed(semicylinder())


@pytest.mark.slow
def test_slit_plate():
    assert_passed(slit_plate())


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["default", "fine"])
def test_tape_linear_refined(preset):
    assert_passed(run_case("tape-linear", load_config(), preset))


@pytest.mark.mpi
def test_two_ranks_agree_with_one_on_a_nonlinear_case():
    """Roll-up to one turn on all ranks and on each rank alone: tip positions agree to 1e-6."""
    parallel = rollup(ROLLUP_MESHES["coarse"], turns=1, comm=MPI.COMM_WORLD)
    serial = rollup(ROLLUP_MESHES["coarse"], turns=1, comm=MPI.COMM_SELF)
    assert MPI.COMM_WORLD.size > 1
    tips_p = np.array([t[1:] for t in parallel.info["tip"]])
    tips_s = np.array([t[1:] for t in serial.info["tip"]])
    assert tips_p.shape == tips_s.shape
    scale = 12.0  # the strip length
    assert np.max(np.abs(tips_p - tips_s)) / scale < 1e-6
    assert parallel.info["newton_iterations"] == serial.info["newton_iterations"]


@pytest.mark.slow
def test_tape_fold_default_mesh():
    """Opposite-sense fold of the benchmark tape: plateau moment, fold radius, flat section, mu."""
    from tapecoil.verification.tape import tape_fold

    result = tape_fold(load_config(), MeshResolution(9, 125))
    assert_passed(result)
    assert result.info["snap_angle"] is not None  # it went through the snap


def test_global_director_frame_turns_the_curved_section_through_pi():
    """A rigid turn of the curved section by pi about the width axis: exact and regular angles.

    In the local frame the director at 45 degrees on the section would land on the singular
    axis t2 at a turn of pi; the global frame keeps every angle finite and the map exact.
    """
    from tapecoil.core.rotation import rotation_matrix

    cfg = load_config()
    strip = create_strip_mesh(MPI.COMM_WORLD, StripGeometry.from_config(cfg), MeshResolution(8, 4))
    model = NaghdiShell(strip, ShellMaterial(cfg.tape.E, cfg.tape.nu, cfg.tape.h), director_frame="global")
    geom = strip.geometry
    s = np.linspace(-cfg.tape.b / 2, cfg.tape.b / 2, 41)
    xi = np.vstack([np.full_like(s, 0.3), s])
    for angle in (math.pi, 3 * math.pi + 0.3):
        Q = rotation_matrix([0, 1, 0], angle)
        d = Q @ geom.frame(xi)[2]
        theta = model.angles_of(d, xi, rotation_near=angle)
        assert np.all(np.isfinite(theta))
        frame, ref = model.director_frame_numpy(xi)
        t0, t1 = ref + theta
        rebuilt = (
            np.cos(t0) * np.sin(t1) * frame[0] - np.sin(t0) * frame[1] + np.cos(t0) * np.cos(t1) * frame[2]
        )
        assert np.allclose(rebuilt, d, atol=1e-13)
        assert np.allclose(theta[1], angle, atol=1e-12)  # a turn about the width axis is theta_1 alone


def test_continuation_stops_with_the_last_converged_state():
    """Cut-backs exhausted: a clear error naming the last converged load, that state kept."""
    from types import SimpleNamespace

    from tapecoil.config import StepControl
    from tapecoil.core.stepping import Continuation, ContinuationError

    state = SimpleNamespace(x=SimpleNamespace(array=np.zeros(3)))
    load = {"t": 0.0}

    def solve():
        ok = load["t"] <= 0.5
        state.x.array[:] = load["t"] if ok else np.nan  # a failed solve leaves garbage behind
        return SimpleNamespace(converged=ok, iterations=3)

    control = StepControl(
        initial_step=0.2, max_step=0.2, min_step=1e-6, grow=1.5, cutback=0.5, max_cutbacks=3
    )
    run = Continuation(solve, lambda t: load.update(t=t), state, control)
    with pytest.raises(ContinuationError, match=r"last converged load 0\.5$") as info:
        run.run(0.0, 1.0)
    assert info.value.load == pytest.approx(0.5)
    assert np.all(state.x.array == pytest.approx(0.5))  # the last converged state, no NaN
    assert load["t"] == pytest.approx(0.5)
    # 0.6 fails, the halved step reaches 0.5; beyond it three cut-backs fail and it stops
    assert [round(s.load, 6) for s in run.history] == [0.2, 0.4, 0.5]


def test_a_step_record_counts_the_failed_attempts_too():
    """A step that converges only after a cut-back: its record keeps the accepted attempt's
    Newton iterations and wall time, and counts every attempt in its totals; the continuation's
    total also holds the attempts of a step that never converged.

    The model: a solve converges (in 3 iterations) when the load moves by at most 0.3 from the
    last converged state, and fails otherwise after 7.
    """
    from types import SimpleNamespace

    from tapecoil.config import StepControl
    from tapecoil.core.stepping import Continuation, ContinuationError

    state = SimpleNamespace(x=SimpleNamespace(array=np.zeros(1)))
    load = {"t": 0.0}

    def solve():
        ok = load["t"] - state.x.array[0] <= 0.3 + 1e-12 and load["t"] <= 0.75
        if ok:
            state.x.array[:] = load["t"]
        return SimpleNamespace(converged=ok, iterations=3 if ok else 7)

    control = StepControl(initial_step=0.5, max_step=0.5, min_step=0.1, grow=1.0, cutback=0.5, max_cutbacks=3)
    run = Continuation(solve, lambda t: load.update(t=t), state, control)
    with pytest.raises(ContinuationError):
        run.run(0.0, 1.0)
    # 0.5 fails, 0.25 converges; 0.5 converges; 0.75 converges; 1.0 fails, 0.875 fails, then
    # the step would be below min_step
    first = run.history[0]
    assert (first.load, first.cutbacks, first.attempts) == (0.25, 1, 2)
    assert (first.iterations, first.total_iterations) == (3, 7 + 3)
    assert first.total_wall_time >= first.wall_time > 0
    assert [(r.load, r.attempts, r.total_iterations) for r in run.history[1:]] == [(0.5, 1, 3), (0.75, 1, 3)]
    assert run.total_iterations == sum(r.total_iterations for r in run.history) + 7 + 7


def test_a_refused_state_is_cut_back_and_then_stops_the_run_with_the_last_accepted_one():
    """A converged state the run refuses (a penetration too deep) is not taken: the step is cut
    back as after a failed solve; where no shorter step is accepted either, the run stops with
    the refusal's message and the last accepted state, with relaxation available or not.

    The model: every solve converges to x = t. In the first run a step longer than 0.1 past
    t = 0.3 penetrates too deep (as an impact a long step does not resolve), which the shorter
    steps avoid; in the second every state beyond t = 0.5 does, which no step avoids.
    """
    from types import SimpleNamespace

    from tapecoil.config import StepControl
    from tapecoil.core.stepping import Continuation, ContinuationError

    state, relaxation = one_dof_with_relaxation()
    load = {"t": 0.0, "from": 0.0}

    def solve():
        load["from"] = state.x.array[0]  # the last accepted state: a refused one is undone
        state.x.array[:] = load["t"]
        return SimpleNamespace(converged=True, iterations=9)

    def long_step_refused():
        return "too deep" if load["t"] > 0.3 and load["t"] - load["from"] > 0.1 + 1e-12 else None

    control = StepControl(
        initial_step=0.2, max_step=0.2, min_step=1e-6, grow=1.0, cutback=0.5, max_cutbacks=3
    )
    run = Continuation(solve, lambda t: load.update(t=t), state, control, refusal=long_step_refused)
    history = run.run(0.0, 1.0)
    # 0.4 is refused after 0.2, and 0.3 taken instead; on from there in the shorter steps
    assert [round(r.load, 6) for r in history] == [0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
    assert [r.cutbacks for r in history[:3]] == [0, 1, 0]

    state.x.array[:], load["t"] = 0.0, 0.0
    beyond = Continuation(
        solve,
        lambda t: load.update(t=t),
        state,
        control,
        relaxation=relaxation,
        refusal=lambda: "the tape penetrates too deep" if load["t"] > 0.5 else None,
    )
    with pytest.raises(
        ContinuationError, match=r"^the tape penetrates too deep, at load .*last converged load 0\.5$"
    ):
        beyond.run(0.0, 1.0)
    assert state.x.array[0] == pytest.approx(0.5) and load["t"] == pytest.approx(0.5)
    assert not any(r.relaxed for r in beyond.history)


def one_dof_with_relaxation():
    """A state of one dof (with the function space the relaxation's norm asks for) and a
    relaxation of it, for the continuation's tests."""
    from types import SimpleNamespace

    from tapecoil.core.stepping import Relaxation

    space = SimpleNamespace(
        dofmap=SimpleNamespace(index_map=SimpleNamespace(size_local=1), index_map_bs=1),
        mesh=SimpleNamespace(comm=MPI.COMM_SELF),
    )
    state = SimpleNamespace(x=SimpleNamespace(array=np.zeros(1)), function_space=space)
    relaxation = Relaxation(
        SimpleNamespace(value=0.0),
        SimpleNamespace(x=SimpleNamespace(array=np.zeros(1))),
        1.0,
        max_iterations=5,
    )
    return state, relaxation


def test_a_failed_relaxation_cuts_the_step_back_and_relaxes_again():
    """A snap at load 0.5 that the relaxation passes only from within 0.02 of it: after the
    relaxation fails from the first cut-back's step, a shorter step relaxes through.

    The model: a plain solve converges on the first branch (x = t, t <= 0.5) or, once there,
    on the second (x = 1 + t); a relaxed solve falls onto the second branch from loads at most
    0.02 past the snap, and fails beyond.
    """
    from types import SimpleNamespace

    from tapecoil.config import StepControl
    from tapecoil.core.stepping import Continuation, ContinuationError

    state, relaxation = one_dof_with_relaxation()
    load = {"t": 0.0}

    def solve():
        t, x = load["t"], state.x.array
        if relaxation.coefficient.value > 0:  # a pseudo-time step
            ok = t - 0.5 <= 0.02
        else:
            ok = t <= 0.5 or x[0] >= 1.0
        if ok:
            x[:] = t if (t <= 0.5 and x[0] < 1.0 and relaxation.coefficient.value == 0) else 1.0 + t
        else:
            x[:] = np.nan
        return SimpleNamespace(converged=ok, iterations=2)

    control = StepControl(
        initial_step=0.1, max_step=0.1, min_step=1e-3, grow=1.0, cutback=0.5, max_cutbacks=1
    )
    run = Continuation(solve, lambda t: load.update(t=t), state, control, relaxation=relaxation)
    history = run.run(0.0, 1.0)
    snap = next(r for r in history if r.relaxed)
    # from 0.5: 0.6 and 0.55 fail (one cut-back), relaxing at 0.525 fails, at 0.5125 it passes
    assert snap.load == pytest.approx(0.5125)
    assert history[-1].load == pytest.approx(1.0) and state.x.array[0] == pytest.approx(2.0)
    # without a step short enough, the run still stops with the last converged state
    state.x.array[:], load["t"] = 0.0, 0.0
    short = StepControl(initial_step=0.1, max_step=0.1, min_step=0.05, grow=1.0, cutback=0.5, max_cutbacks=1)
    stuck = Continuation(solve, lambda t: load.update(t=t), state, short, relaxation=relaxation)
    with pytest.raises(
        ContinuationError, match=r"even with pseudo-transient relaxation .*last converged load 0\.5"
    ):
        stuck.run(0.0, 1.0)
    assert state.x.array[0] == pytest.approx(0.5)


def test_steps_creeping_towards_a_snap_relax_through_it():
    """Near a snap's turning point every step converges only at half the length of the one
    before (it is cut back once, then passes): after ``max_cutbacks`` cut-backs since the last
    clean step the failing step relaxes through the snap instead of creeping on.

    The model: a plain solve converges on the first branch for t < 0.57 or, once there, on the
    second (x = 1 + t); a relaxed solve falls onto the second from loads up to 0.6.
    """
    from types import SimpleNamespace

    from tapecoil.config import StepControl
    from tapecoil.core.stepping import Continuation

    state, relaxation = one_dof_with_relaxation()
    load = {"t": 0.0}

    def solve():
        t, x = load["t"], state.x.array
        relaxing = relaxation.coefficient.value > 0
        ok = t <= 0.6 if relaxing else (t < 0.57 or x[0] >= 1.0)
        if ok:
            x[:] = t if (t < 0.57 and x[0] < 1.0 and not relaxing) else 1.0 + t
        else:
            x[:] = np.nan
        return SimpleNamespace(converged=ok, iterations=9)  # never easy: the steps do not grow

    control = StepControl(
        initial_step=0.1, max_step=0.1, min_step=1e-9, grow=1.5, cutback=0.5, max_cutbacks=3
    )
    run = Continuation(solve, lambda t: load.update(t=t), state, control, relaxation=relaxation)
    history = run.run(0.0, 1.0)
    loads = [round(r.load, 6) for r in history]
    # 0.6 fails, 0.55 passes (1 cut-back); 0.6 and 0.575 fail, 0.5625 passes (3); 0.575 fails
    # again: 4 cut-backs since the last clean step, so it relaxes there
    assert loads[:8] == [0.1, 0.2, 0.3, 0.4, 0.5, 0.55, 0.5625, 0.575]
    assert [r.relaxed for r in history[:8]] == [False] * 7 + [True]
    assert history[-1].load == pytest.approx(1.0) and state.x.array[0] == pytest.approx(2.0)


def test_error_controlled_steps_meet_their_tolerance():
    """With an error estimate, steps whose error exceeds the tolerance are repeated shorter,
    and the accepted ones settle where the error is just below it.

    The estimate here is (step / 0.05)^2, as for a second-order integrator; the first step of
    0.2 is 16 times the tolerance and is rejected.
    """
    from types import SimpleNamespace

    from tapecoil.config import StepControl
    from tapecoil.core.stepping import Continuation

    state = SimpleNamespace(x=SimpleNamespace(array=np.zeros(1)))
    load = {"t": 0.0, "from": 0.0}

    def solve():
        state.x.array[:] = load["t"]
        return SimpleNamespace(converged=True, iterations=2)

    def set_load(t):
        load["from"], load["t"] = state.x.array[0], t

    control = StepControl(
        initial_step=0.2, max_step=1.0, min_step=1e-6, grow=1.5, cutback=0.5, max_cutbacks=3
    )

    def error():
        return ((load["t"] - load["from"]) / 0.05) ** 2

    run = Continuation(solve, set_load, state, control, error=error)
    history = run.run(0.0, 1.0)
    assert history[0].rejected == 1 and sum(r.rejected for r in history) == 1
    assert all(r.error <= 1.0 for r in history)
    # between 0.9 of the tolerance (where the controller aims) and the tolerance, but for the
    # last step, shortened to land on the end
    assert all(0.9 * 0.05 - 1e-12 <= r.step <= 0.05 for r in history[:-1])
    assert history[-1].load == pytest.approx(1.0)
