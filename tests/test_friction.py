"""Coulomb friction on the hub (tapecoil.hub.friction): the capstan's exp(mu theta), sticking
below the slip load, the energy the slip dissipates, the consistent Jacobian, 2 ranks against 1."""

import math

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from tapecoil.core.dofs import global_scalar
from tapecoil.verification.capstan import (
    CAPSTAN_MU,
    CAPSTAN_TOLERANCE,
    CAPSTAN_WRAPS,
    HOLD,
    THICKNESS,
    CapstanProblem,
    capstan,
)


@pytest.mark.parametrize(("mu", "wrap"), [(0.1, math.pi / 2), (0.18, math.pi), (0.5, 3 * math.pi)])
def test_capstan_pull_is_euler_eytelwein(mu, wrap):
    result = capstan(mu, wrap, MPI.COMM_SELF)
    check = result.checks[0]
    assert check.reference == pytest.approx(math.exp(mu * wrap), rel=1e-12)
    assert check.passed, (check.computed, check.reference)


@pytest.mark.slow
@pytest.mark.parametrize("mu", CAPSTAN_MU)
@pytest.mark.parametrize("wrap", CAPSTAN_WRAPS)
def test_capstan_grid(mu, wrap):
    check = capstan(mu, wrap, MPI.COMM_SELF).checks[0]
    assert check.passed, (check.computed, check.reference)


def test_capstan_without_friction_pulls_what_holds():
    # the same strip without friction: the pull is the hold, so the check of exp(mu theta) fails
    result = capstan(0.0, math.pi, MPI.COMM_SELF)
    assert result.checks[0].computed == pytest.approx(HOLD, rel=1e-3)
    assert result.info["dissipated [J]"] == 0.0


def test_strip_sticks_until_the_pull_reaches_the_slip_load():
    mu, wrap = 0.5, math.pi
    result = capstan(mu, wrap, MPI.COMM_SELF)
    _, pulls, slides = np.array(result.info["history"]).T
    slip_load = HOLD * math.exp(mu * wrap)
    below = pulls < 0.98 * slip_load
    assert below.sum() >= 3, "the pull must rise through the sticking range in several steps"
    # below the slip load the held end creeps by the sticking springs' reach alone (mu times the
    # penetration, a few hundredths of h); once the pull has reached it, it slides
    assert np.ptp(slides[below]) < 0.01 * THICKNESS
    assert slides[-1] > 4 * THICKNESS
    assert np.all(pulls <= slip_load * (1 + CAPSTAN_TOLERANCE))


def _stored(problem) -> float:
    m, comm = problem.model, problem.model.mesh.comm
    return global_scalar(m.strain_energy + problem.contact.energy + problem.grip_energy, comm) + (
        problem.friction.spring_energy()
    )


def test_friction_dissipation_closes_the_energy_balance():
    problem = CapstanProblem(0.3, math.pi, MPI.COMM_SELF)
    rows = []

    def on_step(record):
        hold_work = -HOLD * problem.held_end_slide()  # the dead force along -x, its end moved along +x
        rows.append((record.load, problem.pull(), _stored(problem), problem.friction.dissipated, hold_work))

    problem.solve(6e-3, first_step=2e-4, max_step=5e-4, on_step=on_step)
    loads, pulls, stored, dissipated, hold = np.array(rows).T
    # the grip's work: its pull along the turn of its anchor, by the trapezoidal rule from the
    # first converged step (the hold's settling before it is not the grip's)
    grip = np.concatenate([[0.0], np.cumsum(0.5 * (pulls[1:] + pulls[:-1]) * np.diff(loads) * problem.mid)])
    work = grip + (hold - hold[0])
    change = stored - stored[0] + dissipated - dissipated[0]
    # the slip dissipates what the friction force does over it: (T_pull - T_hold) times the slide
    slide = problem.held_end_slide() - rows[0][4] / -HOLD
    assert dissipated[-1] - dissipated[0] == pytest.approx((pulls[-1] - HOLD) * slide, rel=0.02)
    # work in = energy stored + dissipated, step by step; what is left is the quadratures' error
    # (the grip's work by the trapezoidal rule, the dissipation by the step's end traction) on a
    # pull that grows by a few parts in a thousand as the held end slides: 1e-4 of it measured
    np.testing.assert_allclose(change, work, rtol=0, atol=1e-3 * dissipated[-1])


@pytest.mark.parametrize("load", [2e-5, 2e-3])  # the slip spreading from the grip; the whole strip sliding
def test_friction_jacobian_is_the_residuals_derivative(load):
    problem = CapstanProblem(0.5, math.pi / 2, MPI.COMM_SELF)
    problem.solve(load, first_step=load / 4, max_step=load / 2)
    # the next step solved but not accepted: an accepted step leaves each slipping point on the
    # Coulomb cone's surface, where the two branches meet; a step on from it, strictly outside
    from tapecoil.config import SolverConfig

    solver = problem.snes_solver(SolverConfig())
    problem.set_load(1.25 * load)
    assert solver.solve().converged
    solver.destroy()
    F, J = problem.forms()
    F, J = dolfinx.fem.form(F), dolfinx.fem.form(J)
    q = problem.model.q
    rng = np.random.default_rng(3)
    direction = rng.standard_normal(q.x.array.size)
    # a move far below the sticking springs' reach: each point stays on its branch
    direction *= 1e-10 / np.abs(direction).max()
    base = q.x.array.copy()

    def residual(sign):
        q.x.array[:] = base + sign * direction
        vector = dolfinx.fem.assemble_vector(F)
        return vector.array.copy()

    difference = 0.5 * (residual(1.0) - residual(-1.0))
    q.x.array[:] = base
    matrix = dolfinx.fem.assemble_matrix(J).to_scipy()
    action = matrix @ direction
    assert np.linalg.norm(action) > 0
    assert np.linalg.norm(difference - action) < 1e-5 * np.linalg.norm(action)
    # the friction's own part is unsymmetric where points slip
    friction = dolfinx.fem.form(
        ufl.derivative(problem.friction.residual, q, ufl.TrialFunction(q.function_space))
    )
    part = dolfinx.fem.assemble_matrix(friction).to_scipy()
    asymmetry = abs(part - part.T).max() / abs(part).max()
    assert asymmetry > 1e-3


@pytest.mark.mpi
def test_capstan_on_two_ranks_as_on_one():
    comm = MPI.COMM_WORLD
    assert comm.size > 1
    parallel, serial = capstan(0.18, math.pi, comm), capstan(0.18, math.pi, MPI.COMM_SELF)
    assert parallel.checks[0].computed == pytest.approx(serial.checks[0].computed, rel=1e-6)
    assert parallel.info["dissipated [J]"] == pytest.approx(serial.info["dissipated [J]"], rel=1e-6)
    pressed = {"hold": 0.0, "press": PRESS, "radius": PLANE_RADIUS}
    parallel = capstan(0.5, PLANE_WRAP, comm, **pressed)
    serial = capstan(0.5, PLANE_WRAP, MPI.COMM_SELF, **pressed)
    assert parallel.checks[0].computed == pytest.approx(serial.checks[0].computed, rel=1e-6)
    # its slip is the difference of two nearly equal displacements (the grip's and the sticking
    # springs' reach), each converged to Newton's tolerance: 1e-6 apart measured
    assert parallel.info["dissipated [J]"] == pytest.approx(serial.info["dissipated [J]"], rel=1e-5)


# -- coiling with friction on the hub ----------------------------------------------------------
def _friction_tape(hub_angle: float, mu: float = 0.18):
    """The short coarse tape of the coiling tests with friction ``mu`` on the hub."""
    import dataclasses

    from test_coiling import short_tape

    config = short_tape(hub_angle)
    return dataclasses.replace(config, contact=dataclasses.replace(config.contact, hub_friction=mu))


def test_coiling_with_hub_friction_balances_the_work_of_the_hub(tmp_path):
    """The hub's work read from the root's reactions and the friction's traction against the
    energy balance (stored energy, the sticking springs', the slip's dissipation and the pull's
    work): a consistency check of the friction's forces and its dissipation, within 1 %."""
    import csv

    from tapecoil.measures.coiling import hub_torque_measure
    from tapecoil.phases.coiling_run import run_coiling

    summary, model = run_coiling(_friction_tape(1.0), tmp_path / "mu", MPI.COMM_SELF, progress=False)
    assert summary["completed"]
    rows = list(csv.DictReader((tmp_path / "mu" / "coiling_history.csv").open()))
    history = [{k: (v if k == "phase" or v == "" else float(v)) for k, v in r.items()} for r in rows]
    measure = hub_torque_measure(history)
    assert measure["computed"] == pytest.approx(1.0, abs=0.01), measure
    dissipated = float(rows[-1]["friction_dissipated"])
    assert dissipated > 0 and math.isfinite(dissipated)
    # the friction's own share of the hub's torque at the end
    assert model.tape.friction.hub_torque() != 0.0
    assert model.tape.friction.dissipated == pytest.approx(dissipated, rel=1e-12)


@pytest.mark.slow
def test_coiling_with_friction_resumes_as_if_never_stopped(tmp_path):
    """Stopped after some steps and resumed from its checkpoint, a coil with friction goes on
    as if never stopped: the anchors and the dissipation come back with the state (friction
    depends on the path, so the same steps must give the same figures)."""
    import csv

    from test_hybrid_coiling import StopAfter

    from tapecoil.phases.coiling_run import run_coiling

    config = _friction_tape(1.0)
    stopped, _ = run_coiling(config, tmp_path / "resumed", MPI.COMM_SELF, progress=False, stop=StopAfter(5))
    assert stopped["interrupted"] and not stopped["completed"]
    resumed, _ = run_coiling(
        config, tmp_path / "resumed", MPI.COMM_SELF, resume=tmp_path / "resumed" / "stowed", progress=False
    )
    direct, _ = run_coiling(config, tmp_path / "direct", MPI.COMM_SELF, progress=False)
    assert resumed["completed"] and direct["completed"]
    rows = {
        name: list(csv.DictReader((tmp_path / name / "coiling_history.csv").open()))
        for name in ("resumed", "direct")
    }
    assert len(rows["resumed"]) == len(rows["direct"])
    for key in (
        "hub_angle",
        "strain_energy",
        "friction_dissipated",
        "friction_energy",
        "hub_torque_reaction",
    ):
        assert float(rows["resumed"][-1][key]) == pytest.approx(float(rows["direct"][-1][key]), rel=1e-9), key


def test_friction_acts_in_coiling_alone_and_refuses_before_computing():
    import dataclasses

    from tapecoil.app.pipeline import run as run_pipeline
    from tapecoil.config import ConfigError, config_from_dict

    with pytest.raises(ConfigError, match=r"contact\.hub_friction"):
        config_from_dict({"contact": {"hub_friction": 2.5}})
    with pytest.raises(ConfigError, match=r"contact\.hub_friction = 0\.18 .* the payout takes the hub"):
        run_pipeline(_friction_tape(1.0), "results-never-written", phases=("coiling", "payout"))
    free = _friction_tape(1.0)
    free = dataclasses.replace(free, deployment=dataclasses.replace(free.deployment, hub="free"))
    with pytest.raises(ConfigError, match=r"deployment\.hub = 'free'"):
        run_pipeline(free, "results-never-written", phases=("coiling", "deployment"))
    with pytest.raises(ConfigError, match=r"contact\.hub_friction = 0"):
        config_from_dict({"contact": {"hub_friction": 0.18}, "model": {"kind": "hybrid"}})
    with pytest.raises(ConfigError, match=r"solver\.stability"):
        config_from_dict({"contact": {"hub_friction": 0.18}, "solver": {"stability": True}})
    assert dataclasses.replace(_friction_tape(1.0).contact, hub_friction=0.0).hub_friction == 0.0


@pytest.mark.mpi
def test_coiling_with_friction_on_two_ranks_as_on_one(tmp_path_factory):
    """The same short coil on 2 ranks and on one; the 2 ranks' checkpoint read on one rank
    holds the same anchors (its sticking springs' energy and friction torque)."""
    from tapecoil.phases.coiling import read_checkpoint
    from tapecoil.phases.coiling_run import run_coiling

    comm = MPI.COMM_WORLD
    assert comm.size > 1
    base = comm.bcast(str(tmp_path_factory.mktemp("friction")) if comm.rank == 0 else None)
    config = _friction_tape(0.5)
    _, parallel = run_coiling(config, f"{base}/parallel", comm, progress=False)
    _, serial = run_coiling(config, f"{base}/serial-{comm.rank}", MPI.COMM_SELF, progress=False)
    figures = {}
    for name, model in (("parallel", parallel), ("serial", serial)):
        e = model.tape.energies()
        figures[name] = (
            e["strain"],
            e["friction"],
            e["friction_dissipated"],
            model.tape.friction.hub_torque(),
        )
    assert figures["parallel"] == pytest.approx(figures["serial"], rel=1e-6)
    read, _ = read_checkpoint(f"{base}/parallel/stowed", config, MPI.COMM_SELF)
    e = read.tape.energies()
    restored = (e["strain"], e["friction"], e["friction_dissipated"], read.tape.friction.hub_torque())
    assert restored == pytest.approx(figures["parallel"], rel=1e-9)


# a strip pressed on a cylinder of 1 m (a plane, to first order in its 0.05 rad) and pushed
PLANE_RADIUS, PLANE_WRAP, PRESS = 1.0, 0.05, 1000.0


@pytest.mark.parametrize("mu", [0.1, 0.5])
def test_pressed_strip_slides_at_mu_times_its_load(mu):
    result = capstan(mu, PLANE_WRAP, MPI.COMM_SELF, hold=0.0, press=PRESS, radius=PLANE_RADIUS)
    check = result.checks[0]
    # q b R_m (exp(mu theta) - 1): mu q b L and the part the curvature adds, mu theta / 2
    assert check.reference == pytest.approx(
        mu * PRESS * 0.01 * (PLANE_RADIUS + THICKNESS / 2) * PLANE_WRAP, rel=0.02
    )
    assert check.error < 2e-4, (check.computed, check.reference)


def test_pressed_strip_dissipates_mu_n_times_its_slip():
    """Sliding, the friction's work over each step is mu N times the slip on the hub's surface,
    N the hub's push summed (a consistency check of the return mapping's dissipation)."""
    mu = 0.3
    problem = CapstanProblem(mu, PLANE_WRAP, MPI.COMM_SELF, hold=0.0, press=PRESS, radius=PLANE_RADIUS)
    m = problem.model
    normal = dolfinx.fem.form(problem.contact.hub_pressure * m.jacobian * m.dx)
    face_angle = dolfinx.fem.form(problem.friction.angle * m.jacobian * m.dx)
    area = global_scalar(m.jacobian * m.dx, MPI.COMM_SELF)
    rows = []

    def on_step(record):
        angle = global_scalar(face_angle, MPI.COMM_SELF) / area  # the face's mean angle on the hub
        rows.append((global_scalar(normal, MPI.COMM_SELF), problem.friction.dissipated, angle))

    problem.solve(6e-4, first_step=3e-5, max_step=6e-5, on_step=on_step)
    normal_force, dissipated, angle = np.array(rows).T
    slip = -np.diff(angle) * problem.contact.r_hub  # the face's angle falls as it moves along +x
    sliding = slip > 0.5 * slip.max()
    assert sliding.sum() >= 5
    work = np.diff(dissipated)[sliding]
    np.testing.assert_allclose(work, mu * normal_force[1:][sliding] * slip[sliding], rtol=1e-6)
    # the push is the press and the pull's tension over the radius: q A (1 + mu theta / 2)
    assert normal_force[-1] == pytest.approx(PRESS * area * (1 + mu * PLANE_WRAP / 2), rel=1e-3)


@pytest.mark.slow
def test_deployment_with_friction_on_a_held_hub_accounts_for_what_it_dissipates():
    """The energy-conserving scheme (rho_inf = 1) leaves no remainder without friction
    (tests/test_deployment.py); with it, what the slip dissipates is taken out of the energy
    balance, and the remainder is the sticking springs' own step error (they are stepped by
    backward Euler): no energy made, and the remainder no larger than the slip's dissipation
    (0.97 of it measured; without the slip's account it would be twice that)."""
    import dataclasses

    from test_deployment import coil, deploy, short_stowed_config

    config = short_stowed_config(t_end=0.012, rho_inf=1.0)
    config = dataclasses.replace(config, contact=dataclasses.replace(config.contact, hub_friction=0.3))
    model, result = deploy(coil(config, MPI.COMM_SELF), config)
    assert model.tape.friction is not None and model.scheme == "conserving"
    h = result.history
    stowed = h[0]["strain_energy"] + h[0]["contact_energy"] + h[0]["friction_energy"]
    slip = h[-1]["friction_dissipated"]
    remainder = np.array([r["scheme_dissipation"] for r in h])
    assert slip > 1e-6 * stowed
    assert remainder.min() > -1e-9 * stowed
    assert remainder[-1] < 1.2 * slip
    assert h[-1]["lambda"] > 0.9
