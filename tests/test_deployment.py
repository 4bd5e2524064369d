"""Deployment: release of a short coiled tape, inertia, energy balance, lambda, output, MPI."""

import dataclasses

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import Config, DeploymentConfig, TapeConfig


def short_stowed_config(t_end=0.012, rho_inf=0.5, rtol=None) -> Config:
    """A 0.12 m tape of the benchmark section, coiled by 2 rad, released for t_end; ``rtol``
    the time steps' Newton tolerance (default: deployment.rtol's)."""
    cfg = Config()
    newton = {} if rtol is None else {"rtol": rtol}
    return dataclasses.replace(
        cfg,
        tape=dataclasses.replace(TapeConfig(), L=0.12),
        coiling=dataclasses.replace(cfg.coiling, hub_angle=2.0),
        mesh=dataclasses.replace(cfg.mesh, preset="coarse"),
        deployment=dataclasses.replace(DeploymentConfig(), t_end=t_end, rho_inf=rho_inf, **newton),
    )


def coil(config, comm):
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    model = CoilingProblem(config, comm)
    run = CoilingRun(model)
    run.flatten()
    run.coil(config.coiling.hub_angle)
    return model


def deploy(coiling, config, quantity=None):
    """Deploy from ``coiling``'s state with ``config``'s deployment settings; the stowed state
    (u, theta, the winding angles and the root's angle) is restored afterwards, so that tests
    can share it.

    ``quantity(model)``: a UFL integrand per unit reference area, integrated after every step
    (the release's row first); then the values come back too, one per history row."""
    from tapecoil.core.dofs import global_scalar
    from tapecoil.phases.deployment import DeploymentProblem
    from tapecoil.phases.deployment_run import DeploymentRun

    saved = coiling.model.q.x.array.copy(), coiling.contact.psi.x.array.copy()
    angle = coiling.tape.root.angle  # a free hub turns the root
    try:
        model = DeploymentProblem(coiling.tape, config)
        values, on_step = [], None
        if quantity is not None:
            import dolfinx

            m = model.model
            form = dolfinx.fem.form(quantity(model) * m.jacobian * m.dx)
            on_step = lambda _row: values.append(global_scalar(form, m.mesh.comm))  # noqa: E731
        run = DeploymentRun(model, on_step=on_step)
        run.run()
        return (model, run.result) if quantity is None else (model, run.result, np.array(values))
    finally:
        coiling.model.q.x.array[:], coiling.contact.psi.x.array[:] = saved
        coiling.tape.root.set(1.0, angle)
        coiling.contact.turn(angle)


@pytest.fixture(scope="module")
def stowed_short():
    return coil(short_stowed_config(), MPI.COMM_SELF)


@pytest.fixture(scope="module")
def deployed_short(stowed_short):
    return deploy(stowed_short, short_stowed_config())


def test_release_unspools_the_tape_and_balances_energy(deployed_short):
    model, result = deployed_short
    h = result.history
    assert not result.completed and "t_end" in result.message  # stopped at t_end, not failed
    assert h[-1]["time"] == pytest.approx(0.012)
    stowed = h[0]["strain_energy"] + h[0]["contact_energy"]
    # the stored energy turns into motion (measured: 7 % of it kinetic after 12 ms)
    assert h[-1]["kinetic_energy"] > 0.04 * stowed
    assert h[-1]["strain_energy"] < h[0]["strain_energy"] - h[-1]["kinetic_energy"]
    # the tape leaves the coil (measured: lambda 0.867 -> 0.96)
    assert h[-1]["lambda"] > h[0]["lambda"] + 0.05
    # numerical dissipation (rho_inf = 0.5) small and never negative beyond round-off
    dissipated = np.array([r["dissipated_energy"] for r in h])
    assert dissipated.max() < 0.02 * stowed
    assert dissipated.min() > -1e-4 * stowed
    # generalized-alpha only takes energy, step by step (measured: 0.49 % over the 12 ms); the
    # residual's work is at the Newton tolerance (measured: 1.7e-5 of the stowed energy in a
    # step at deployment.rtol = 1e-5, 1e-9 at 1e-8)
    scheme = np.array([r["scheme_dissipation"] for r in h])
    assert np.diff(scheme).min() > -1e-8 * stowed
    assert max(abs(r["residual_work"]) for r in h) < 1e-4 * stowed
    # the release did little work: the hold's spring and forces let go without a shock
    assert abs(h[-1]["external_work"]) < 0.01 * stowed
    assert max(r["max_penetration"] for r in h) < 0.5 * model.config.tape.h


@pytest.mark.slow
def test_trapezoidal_rule_conserves_energy(stowed_short):
    """rho_inf = 1, the energy-conserving trapezoidal rule: no numerical dissipation, no growth.

    Over 12 ms of the short tape (measured: 196 steps, the energy balance closed to 2e-9 of the
    stowed energy) the remainder strain + contact + kinetic - stowed - work of the release stays
    at the Newton tolerance's level, and it is the converged residual's work: what is left
    for the scheme is round-off (measured: 2e-14 of the stowed energy, against 1.5e-9 for the
    residual's work). Newton to 1e-8 of each step's first residual: the balance closes to
    the tolerance, and the default's would hide the scheme's part.
    """
    model, result = deploy(stowed_short, short_stowed_config(rho_inf=1.0, rtol=1e-8))
    assert model.scheme == "conserving"
    h = result.history
    stowed = h[0]["strain_energy"] + h[0]["contact_energy"]
    dissipated = np.array([r["dissipated_energy"] for r in h])
    assert h[-1]["kinetic_energy"] > 0.04 * stowed
    assert np.abs(dissipated).max() < 1e-7 * stowed
    scheme = np.array([r["scheme_dissipation"] for r in h])
    assert np.abs(scheme).max() < 1e-12 * stowed < np.abs(dissipated).max()


def test_secant_forces_give_the_exact_energy_change(stowed_short):
    """The discrete gradients of the shell's and the contact's energies, tested with a step,
    give exactly the change of the energy between its two ends, for a step of any size."""
    import dolfinx
    import ufl

    from tapecoil.core.dofs import global_scalar

    model = stowed_short.model
    contact = stowed_short.contact
    q = model.q.x.array
    stowed = q.copy()
    q_old = dolfinx.fem.Function(model.W)
    q_old.x.array[:] = stowed
    energy = dolfinx.fem.form(model.strain_energy + contact.energy)
    dd = model.director_variation(q_old)
    work = sum(model.energy_secant_forms(q_old)) + contact.energy_secant_form(q_old, dd)
    work = dolfinx.fem.form(work)
    rng = np.random.default_rng(3)
    nodes = contact.nodes
    try:
        for size in (1e-6, 1e-4):  # 1 % of h and a whole h (deep into the coil); rotations alike
            step = np.zeros_like(q)
            step[nodes.u_dofs] = size * rng.standard_normal(nodes.u_dofs.shape)
            step[nodes.theta_dofs] = 100 * size * rng.standard_normal(nodes.theta_dofs.shape)
            q[:] = stowed
            e0 = global_scalar(energy, model.mesh.comm)
            q[:] = stowed + step
            e1 = global_scalar(energy, model.mesh.comm)
            f = dolfinx.fem.Function(model.W)
            dolfinx.fem.assemble_vector(f.x.array, work)
            f.x.scatter_reverse(dolfinx.la.InsertMode.add)
            assert float(np.dot(f.x.array, step)) == pytest.approx(e1 - e0, rel=1e-9)
            # not the tangent at either end: the plain trapezoid of the end forces misses it
            tangent = dolfinx.fem.form(ufl.derivative(model.strain_energy + contact.energy, model.q))
            g1 = dolfinx.fem.Function(model.W)
            dolfinx.fem.assemble_vector(g1.x.array, tangent)
            assert abs(float(np.dot(g1.x.array, step)) - (e1 - e0)) > 1e-6 * abs(e1 - e0)
    finally:
        q[:] = stowed


def test_lambda_of_a_straight_tape_leaving_the_hub(deployed_short):
    """The lift-off measure on constructed states: the stowed coil, and a tape laid straight."""
    model, _ = deployed_short
    nodes = model.contact.nodes
    q, psi = model.model.q.x.array, model.contact.psi.x.array
    saved, saved_psi = q.copy(), psi.copy()
    try:
        # every point on the hub's top tangent line, straight along +x from the root at x = 0
        # (hub angle 0 geometry), the section flat: lambda = 1 (nothing wound)
        model.tape.root.set(1.0, 0.0)
        model.contact.reset()
        target = np.vstack([nodes.xi[0], nodes.xi[1], np.zeros_like(nodes.xi[0])])
        q[nodes.u_dofs] = (target - nodes.reference).T
        theta = model.model.angles_of(np.tile([[0.0], [0.0], [1.0]], nodes.xi.shape[1]), nodes.xi)
        q[nodes.theta_dofs] = theta.T
        model.contact.reset()
        lift = model.lift_off()
        assert lift["lambda"] == pytest.approx(1.0, abs=0.02)
    finally:
        q[:], psi[:] = saved, saved_psi
        model.tape.root.set(1.0, model.hub_angle)
        model.contact.turn(model.hub_angle)


def test_lambda_at_release_is_the_coilings_free_fraction(stowed_short):
    """One definition of lambda in both phases (measures.deployment.lift_off): the deployment's
    lambda0 is the coiling's free fraction at the stowed state, by construction (a consistency
    check). The tangent point of the winding angles, the coiling's coiled length, lies beyond
    the lift-off point, where the section's flattening lifts the centre line off the hub
    gradually: by 9.9 mm here, under one element (12 mm); 1.3 mm on the coarse benchmark,
    11.8 mm on the default one."""
    from tapecoil.measures.coiling import coil_measures

    free = coil_measures(stowed_short.tape)["free_fraction"]
    _, result = deploy(stowed_short, short_stowed_config(t_end=2e-4))
    assert result.history[0]["lambda"] == free["lambda"]
    config = short_stowed_config()
    element = config.tape.L / stowed_short.tape.strip.resolution.along
    gap = (free["lambda"] - free["tangent_point"]) * config.tape.L
    assert 0 <= gap < 2 * element


def test_bad_deployment_config_is_rejected_before_computing():
    from tapecoil.config import ConfigError, config_from_dict

    with pytest.raises(ConfigError, match=r"deployment\.max_dt .* at least deployment\.dt"):
        config_from_dict({"deployment": {"dt": 1e-3, "max_dt": 1e-4}})
    with pytest.raises(ConfigError, match=r"deployment\.release_time"):
        config_from_dict({"deployment": {"release_time": -1.0}})


@pytest.mark.mpi
def test_two_ranks_deploy_as_one():
    """Also with error-controlled steps: the estimate is collective, so the steps agree."""
    config = short_stowed_config(t_end=0.002)
    config = dataclasses.replace(
        config, deployment=dataclasses.replace(config.deployment, error_tolerance=0.01)
    )
    _, parallel = deploy(coil(config, MPI.COMM_WORLD), config)
    _, serial = deploy(coil(config, MPI.COMM_SELF), config)
    assert len(parallel.history) == len(serial.history)
    assert [r["rejected_steps"] for r in parallel.history] == [r["rejected_steps"] for r in serial.history]
    keys = ("kinetic_energy", "strain_energy", "lambda", "tip_x", "tip_z", "dissipated_energy")
    for key in (*keys, "root_force_x", "root_force_z", "root_moment_y", "root_torque"):
        a, b = parallel.history[-1][key], serial.history[-1][key]
        assert a == pytest.approx(b, rel=1e-5, abs=1e-9), key


def free_hub_config(inertia: float, t_end: float = 0.004) -> Config:
    """The short tape's deployment with the hub free to turn, of rotary inertia ``inertia``."""
    config = short_stowed_config(t_end=t_end)
    return dataclasses.replace(
        config,
        hub=dataclasses.replace(config.hub, inertia=inertia),
        deployment=dataclasses.replace(config.deployment, hub="free"),
    )


def short_tape_inertia(config) -> float:
    """The short tape's own rotary inertia were it wound whole (theory.stowed_rotary_inertia,
    the J_tape of docs/notes/deployment.md) [kg m^2], about 5.7e-7."""
    from tapecoil import theory

    tp = config.tape
    return theory.stowed_rotary_inertia(config.hub.radius, tp.h, tp.L, tp.rho_l)


@pytest.mark.mpi
def test_two_ranks_deploy_a_free_hub_as_one():
    config = free_hub_config(short_tape_inertia(short_stowed_config()), t_end=0.002)
    _, parallel = deploy(coil(config, MPI.COMM_WORLD), config)
    _, serial = deploy(coil(config, MPI.COMM_SELF), config)
    assert len(parallel.history) == len(serial.history)
    for key in (
        "hub_angle",
        "hub_rate",
        "angular_momentum",
        "kinetic_energy",
        "lambda",
        "tip_x",
        "root_torque",
    ):
        a, b = parallel.history[-1][key], serial.history[-1][key]
        assert a == pytest.approx(b, rel=1e-5, abs=1e-9), key


def test_a_free_hub_turns_back_and_keeps_the_angular_momentum(stowed_short):
    """A hub of 25 times the tape's own rotary inertia (lighter, it would deploy the short
    tape within the release), free from release: it turns back, paying the tape
    out, and deploys it faster than a fixed hub (the free-hub model: sqrt(1 + I_s/I_h) on the
    rate). Once the hold is released, nothing outside turns the tape and the hub (the hub's
    contact is radial and frictionless), so their angular momentum about the axis, read from the
    tape's velocities and the hub's rate, stays what the release left: measured to 0.2 % of the
    hub's own over the last 2 ms; 1 % allowed for the first-order error of the generalized-alpha
    levels. The energy account takes the hub's kinetic energy: nothing is created."""
    inertia = 25 * short_tape_inertia(short_stowed_config())
    config = free_hub_config(inertia)
    model, result = deploy(stowed_short, config)
    h = result.history
    released = [r for r in h if r["time"] > 1.5 * config.deployment.release_time]
    spin = max(abs(inertia * r["hub_rate"]) for r in h)
    drift = max(abs(r["angular_momentum"] - released[0]["angular_momentum"]) for r in released)
    assert drift < 0.01 * spin
    assert h[-1]["hub_angle"] < h[0]["hub_angle"] - 0.02 and h[-1]["hub_rate"] < 0
    assert h[-1]["hub_kinetic_energy"] == pytest.approx(0.5 * inertia * h[-1]["hub_rate"] ** 2)
    stowed = h[0]["strain_energy"] + h[0]["contact_energy"]
    dissipated = np.array([r["dissipated_energy"] for r in h])
    assert dissipated.min() > -1e-3 * stowed and dissipated.max() < 0.02 * stowed
    _, fixed = deploy(stowed_short, short_stowed_config(t_end=h[-1]["time"]))
    assert h[-1]["lambda"] > fixed.history[-1]["lambda"] + 0.01
    assert model.coupling.iterations >= len(h) - 1  # the hub's equation took part in every step


def test_a_free_hub_far_heavier_than_the_tape_deploys_as_a_fixed_one(stowed_short):
    """Consistency of the coupling: with J = 10^4 kg m^2 the hub barely turns (the root torque
    of about 0.05 N m turns it by 1e-11 rad in 2 ms) and the tape moves as on a fixed hub.
    Both solved to a residual 1e-8 of each step's first: the two Newton iterations differ, and
    at the default 1e-5 their states differ by what that leaves (measured 1e-6)."""

    def tight(config):
        return dataclasses.replace(config, deployment=dataclasses.replace(config.deployment, rtol=1e-8))

    _, free = deploy(stowed_short, tight(free_hub_config(1e4, t_end=0.002)))
    _, fixed = deploy(stowed_short, tight(short_stowed_config(t_end=0.002)))
    a, b = free.history[-1], fixed.history[-1]
    assert abs(a["hub_angle"] - free.history[0]["hub_angle"]) < 1e-9
    for key in ("tip_x", "tip_z", "lambda", "kinetic_energy"):
        assert a[key] == pytest.approx(b[key], rel=1e-6, abs=1e-12), key


def test_error_controlled_steps_follow_the_motion_to_its_tolerance(stowed_short):
    """deployment.error_tolerance: every accepted step's local error estimate is within the
    tolerance, the steps shorten where the motion changes fast (the end of the release) and
    lengthen where it does not, and the tip ends where a run in uniform steps of 25 us puts it.

    Measured over the first 4 ms: 54 steps of 19 to 100 us (7 rejected); the tip 1.0 % of its
    travel (1.05 mm) from the uniform run's, which itself moves by 0.6 % with steps of 10 us.
    """
    config = short_stowed_config(t_end=0.004)
    controlled = dataclasses.replace(
        config, deployment=dataclasses.replace(config.deployment, error_tolerance=0.03, max_dt=1e-2)
    )
    _, result = deploy(stowed_short, controlled)
    rows = result.history[1:]
    assert result.history[-1]["time"] == pytest.approx(0.004)
    assert all(0.0 < r["step_error"] <= 1.0 for r in rows)
    assert sum(r["rejected_steps"] for r in rows) > 0
    steps = np.array([r["step"] for r in rows])
    assert steps.max() > 3 * steps.min()  # sized by the motion, not by a cap
    uniform = dataclasses.replace(
        config, deployment=dataclasses.replace(config.deployment, dt=2.5e-5, max_dt=2.5e-5)
    )
    _, reference = deploy(stowed_short, uniform)
    tip = lambda r: np.array([r["tip_x"], r["tip_y"], r["tip_z"]])  # noqa: E731
    travelled = np.linalg.norm(tip(reference.history[-1]) - tip(reference.history[0]))
    assert np.linalg.norm(tip(result.history[-1]) - tip(reference.history[-1])) < 0.02 * travelled


@pytest.mark.slow
def test_trapezoidal_rule_conserves_energy_through_a_whole_deployment(stowed_short):
    """rho_inf = 1 to lambda = 1: the short tape unwinds completely (measured: 1,094 steps,
    25 ms) and strain + contact + kinetic energy stay the stowed energy plus the release's
    work to 2e-8 of it: no spurious growth, no numerical dissipation (Newton to 1e-8 of each
    step's first residual, the balance's own tolerance)."""
    config = short_stowed_config(t_end=0.1, rho_inf=1.0, rtol=1e-8)
    _, result = deploy(stowed_short, config)
    assert result.completed, result.message
    h = result.history
    stowed = h[0]["strain_energy"] + h[0]["contact_energy"]
    dissipated = np.array([r["dissipated_energy"] for r in h])
    assert np.abs(dissipated).max() < 1e-6 * stowed
    assert h[-1]["kinetic_energy"] > 0.5 * stowed


def test_deployment_from_a_checkpoint_builds_no_coiling_problem(stowed_short, tmp_path, monkeypatch):
    """Deploying from a stowed checkpoint reads the tape alone: no coiling forms, no coiling SNES."""
    from tapecoil.phases import coiling
    from tapecoil.phases.coiling import write_checkpoint
    from tapecoil.phases.deployment_run import run_deployment

    meta = {"phase": "coiling", "hub_angle": stowed_short.root.angle, "tension": 1.0, "completed": True}
    write_checkpoint(stowed_short, tmp_path / "stowed", meta)

    def refuse(*_args, **_kwargs):
        raise AssertionError("the deployment built a coiling model")

    monkeypatch.setattr(coiling.CoilingProblem, "__init__", refuse)
    config = short_stowed_config(t_end=0.0005)
    config = dataclasses.replace(config, output=dataclasses.replace(config.output, checkpoint=False))
    summary, model = run_deployment(
        config, tmp_path / "out", MPI.COMM_SELF, stowed=tmp_path / "stowed", progress=False
    )
    assert summary["time"] == pytest.approx(0.0005)
    assert summary["run"]["steps"] > 0
    # the deployment starts from the checkpoint's state
    assert model.hub_angle == pytest.approx(stowed_short.root.angle)


def test_the_root_loads_balance_the_tapes_angular_momentum(stowed_short):
    """The torque the root puts on the hub is the rate at which the tape loses angular momentum
    about the hub's axis, once released (the hub contact is frictionless and radial, so it adds
    no torque): tau = -dH/dt, H = int rho h (x - c) x v + rho h^3/12 d x d' read from the
    velocities, independently of the reactions. Central differences of H over uneven steps and
    the generalized-alpha balance (at its alpha levels, not at t_{n+1}) are first order in the
    step: measured 1.1 % (median) and 3.5 % (largest) of the peak torque. At release the root
    torque is the coiling's hub torque (the same state, held), with the opposite sign (the load
    on the hub, against the torque that turned it); the history's H is the tape's alone, the
    hub being fixed."""
    config = short_stowed_config(t_end=0.008)
    hub_torque = stowed_short.hub_torque()
    _, result = deploy(stowed_short, config)
    history = result.history
    H = np.array([row["angular_momentum"] for row in history])
    assert history[0]["root_torque"] == pytest.approx(-hub_torque, rel=1e-9)
    t = np.array([row["time"] for row in history])
    tau = np.array([row["root_torque"] for row in history])[1:-1]
    rate = (H[2:] - H[:-2]) / (t[2:] - t[:-2])
    released = t[1:-1] > 1.5 * config.deployment.release_time
    scale = np.abs(tau[released]).max()
    mismatch = np.abs(tau[released] + rate[released]) / scale
    assert np.median(mismatch) < 0.02 and mismatch.max() < 0.05
    assert scale > 0.5 * abs(hub_torque)  # the torque is of the coil's size, not noise


def test_gravity_is_carried_by_the_root(stowed_short):
    """Gravity along the hub's axis (y), which the frictionless, radial hub contact cannot carry:
    the root's force on the hub along y is the tape's weight less the rate of its momentum,
    F_y = m g_y - dP_y/dt, P_y = int rho h v_y read from the velocities (independently of the
    reactions), to the first-order error of the differences and of the alpha levels (measured:
    2.3 % of the weight over the steps' median, 4.6 % at most, the root's own share of the weight
    counted as the attachment's; over these 8 ms the root carries a third to a half of the
    weight, the rest accelerates the tape). The energy account takes
    gravity's work: no energy is created."""
    g = -9.81
    config = short_stowed_config(t_end=0.008)
    config = dataclasses.replace(
        config, deployment=dataclasses.replace(config.deployment, gravity=[0.0, g, 0.0])
    )
    tp = config.tape
    _, run_result, P = deploy(stowed_short, config, lambda m: tp.density * tp.h * m.integrator.v_old[1])
    mass = tp.rho_l * tp.L  # rho h over the reference area
    history = run_result.history
    t = np.array([row["time"] for row in history])
    force = np.array([row["root_force_y"] for row in history])[1:-1]
    rate = (P[2:] - P[:-2]) / (t[2:] - t[:-2])
    released = t[1:-1] > 1.5 * config.deployment.release_time
    weight = abs(mass * g)
    mismatch = np.abs(force[released] - (mass * g - rate[released])) / weight
    assert np.median(mismatch) < 0.03 and mismatch.max() < 0.1
    h = history
    stowed = h[0]["strain_energy"] + h[0]["contact_energy"]
    dissipated = np.array([r["dissipated_energy"] for r in h])
    assert dissipated.min() > -1e-3 * stowed and dissipated.max() < 0.02 * stowed
    assert abs(h[-1]["external_work"]) > 0  # gravity has worked on the tape


@pytest.mark.parametrize("rho_inf", [0.5, 1.0])
def test_a_steps_energy_is_read_before_it_is_accepted(stowed_short, rho_inf):
    """What the step's refusal weighs (:meth:`DeploymentProblem.step_energy`, before the step
    is accepted) is the energy the accepted state reports, but for the contact energy the
    winding angles' update adds after it; and no step of a sound run is refused for energy."""
    from tapecoil.phases.deployment import DeploymentProblem
    from tapecoil.phases.deployment_run import DeploymentRun

    config = short_stowed_config(t_end=0.003, rho_inf=rho_inf)
    saved = stowed_short.model.q.x.array.copy(), stowed_short.contact.psi.x.array.copy()
    angle = stowed_short.tape.root.angle
    try:
        model = DeploymentProblem(stowed_short.tape, config)
        read = model.step_energy
        latest, pairs = [], []

        def step_energy():
            latest.append(read())
            return latest[-1]

        model.step_energy = step_energy

        def on_step(row):
            if row["step"] > 0:
                total = row["strain_energy"] + row["contact_energy"] + row["kinetic_energy"]
                pairs.append((latest[-1], total, row["contact_update_energy"]))

        run = DeploymentRun(model, on_step=on_step)
        run.run()
    finally:
        stowed_short.model.q.x.array[:], stowed_short.contact.psi.x.array[:] = saved
        stowed_short.tape.root.set(1.0, angle)
        stowed_short.contact.turn(angle)
    assert run.result.completed or "t_end" in run.result.message
    candidate, accepted, update = np.array(pairs).T
    assert len(pairs) > 10
    stowed = run.result.history[0]["strain_energy"] + run.result.history[0]["contact_energy"]
    np.testing.assert_allclose(
        candidate + np.diff(update, prepend=0.0), accepted, rtol=0, atol=1e-12 * stowed
    )
