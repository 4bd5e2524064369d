"""Every [solver] key acts, in the verification cases, the coiling and the deployment (cheap runs)."""

import dataclasses
import itertools
import math

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import Config, SolverConfig, StepControl
from tapecoil.core.stepping import ContinuationError
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.verification.cases import run_case
from tapecoil.verification.tape import tape_fold


def solver_config(**kw) -> Config:
    return dataclasses.replace(Config(), solver=SolverConfig(**kw))


def test_zero_leaves_min_step_and_max_cutbacks_to_the_phase():
    own = SolverConfig().control(initial_step=0.1, max_step=0.2, min_step=1e-4, max_cutbacks=4)
    assert own == StepControl(0.1, 0.2, 1e-4, 1.5, 0.5, 4)
    # min_step > 0 is a fraction of the phase's whole range: here 10 times the span
    mine = SolverConfig(min_step=1e-3, max_cutbacks=2, grow=1.2, cutback=0.3)
    assert mine.control(0.1, 0.2, 1e-4, 4, range_fraction=10.0) == StepControl(0.1, 0.2, 1e-2, 1.2, 0.3, 2)


@pytest.fixture(scope="module")
def rollup_default():
    return run_case("rollup", Config(), "coarse")


@pytest.mark.parametrize("settings", [{"rtol": 1e-3}, {"atol": 1e-2}])
def test_newton_tolerances_reach_a_case(rollup_default, settings):
    """Measured: 10 Newton iterations in each of the 20 steps by default, 8 with either."""
    result = run_case("rollup", solver_config(**settings), "coarse")
    assert result.passed
    assert result.info["steps"] == rollup_default.info["steps"]
    assert sum(result.info["newton_iterations"]) < sum(rollup_default.info["newton_iterations"])


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        # one Newton iteration never converges: the first step is cut back until a limit stops it;
        # steps in the load's units (the end moment, 2 M_max = 104.72 N m; the first step 5 % of it)
        ({"max_newton": 1}, r"after 8 cut-backs \(step 0\.0205\)"),  # the case's own 8
        ({"petsc_options": {"snes_max_it": 1}}, r"after 8 cut-backs"),
        ({"max_newton": 1, "max_cutbacks": 2}, r"after 2 cut-backs \(step 1\.31\)"),
        ({"max_newton": 1, "max_cutbacks": 3, "cutback": 0.25}, r"after 3 cut-backs \(step 0\.0818\)"),
        # 0.05 of the load halved below 0.004 of it: 0.003125 of it is refused
        ({"max_newton": 1, "min_step": 0.004}, r"after 3 cut-backs \(step 0\.654\)"),
    ],
)
def test_cut_back_settings_reach_a_case(settings, message):
    with pytest.raises(ContinuationError, match=message):
        run_case("rollup", solver_config(**settings), "coarse")


@pytest.mark.parametrize("case", ["semicylinder", "slit-plate"])
def test_the_other_load_stepped_cases_take_the_settings(case):
    with pytest.raises(ContinuationError, match=r"after 2 cut-backs"):
        run_case(case, solver_config(max_newton=1, max_cutbacks=2), "coarse")


def test_the_tape_fold_takes_the_settings():
    """A short fold (the linear range of a 0.1 m piece): steps of 1 % of the rotation grow to 2 %."""
    res = MeshResolution(2, 10)

    def steps(**kw):
        result = tape_fold(solver_config(**kw), res, length=0.1, final_angle=0.01)
        return result.info["steps"], sum(result.info["newton_iterations"])

    base_steps, base_its = steps()
    assert steps(grow=1.0)[0] == 100 > base_steps
    loose_steps, loose_its = steps(rtol=1e-3)
    assert loose_steps == base_steps and loose_its < base_its


@pytest.fixture(scope="module")
def coiled():
    """A 0.1 m tape coiled by 0.3 rad with every [solver] key away from its default; the step
    controls the coiling and the deployment built are recorded."""
    from tapecoil.phases import deployment, deployment_run, time_loop
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    cfg = Config()
    cfg.tape.L = 0.1
    cfg.mesh.preset = "coarse"
    cfg.coiling.hub_angle = 0.3
    cfg.deployment = dataclasses.replace(cfg.deployment, t_end=5e-4, release_time=0.0, rtol=1e-6)
    cfg.solver = SolverConfig(
        rtol=1e-7, atol=1e-9, max_newton=20, min_step=1e-3, grow=1.0, cutback=0.4, max_cutbacks=5
    )
    controls = []

    class Recorded(CoilingRun):
        def continuation(self, set_load, control, predict=None):
            controls.append(("coiling", control))
            return super().continuation(set_load, control, predict)

    model = CoilingProblem(cfg, MPI.COMM_WORLD)
    run = Recorded(model)
    run.flatten()
    run.coil(cfg.coiling.hub_angle)

    original = time_loop.Continuation

    class RecordedContinuation(original):
        def __init__(self, solve, set_load, state, control, **kw):
            controls.append(("deployment", control))
            super().__init__(solve, set_load, state, control, **kw)

    time_loop.Continuation = RecordedContinuation
    try:
        deploy = deployment.DeploymentProblem(model.tape, cfg)
        result = deployment_run.DeploymentRun(deploy).run()
    finally:
        time_loop.Continuation = original
    return cfg, model, run.result.history, deploy, result, controls


def test_the_coiling_takes_every_setting(coiled):
    _, model, history, _, _, controls = coiled
    assert model.solver.snes.getOptionsPrefix() == "coil_"
    assert model.solver.snes.getTolerances() == (1e-7, 1e-9, 0.0, 20)
    (_, flatten), (_, coil) = [c for c in controls if c[0] == "coiling"]
    for control in (flatten, coil):
        assert (control.grow, control.cutback, control.max_cutbacks) == (1.0, 0.4, 5)
    assert flatten.min_step == pytest.approx(1e-3)  # of the flattening
    assert coil.min_step == pytest.approx(1e-3)  # of the hub angle, which is here the span
    # grow = 1: the hub turns in its first steps of 0.05 rad throughout, instead of growing
    steps = [r["step"] for r in history if r["phase"] == "coil"]
    assert np.allclose(steps, 0.05) and len(steps) == 6


def test_the_deployment_takes_every_setting(coiled):
    _, _, _, deploy, result, controls = coiled
    assert deploy.solver.snes.getOptionsPrefix() == "deploy_"
    # the time steps' rtol is the deployment's own; atol and max_newton are [solver]'s
    assert deploy.solver.snes.getTolerances() == (1e-6, 1e-9, 0.0, 20)
    [(_, control)] = [c for c in controls if c[0] == "deployment"]
    assert (control.grow, control.cutback, control.max_cutbacks) == (1.0, 0.4, 5)
    assert control.min_step == pytest.approx(1e-3)  # of t_end, which is here the span
    # from deployment.dt, each step the one before times cutback^cutbacks: grow = 1 never
    # lengthens it (by default 1e-4, 1.5e-4, 2.25e-4 and the rest); the last lands on t_end
    rows = result.history[1:]
    assert rows[0]["step"] == pytest.approx(1e-4)
    for before, row in itertools.pairwise(rows[:-1]):
        assert row["step"] == pytest.approx(before["step"] * 0.4 ** row["cutbacks"])
    assert math.isclose(result.history[-1]["time"], 5e-4)


def test_phase_tables_override_the_solver_table():
    from tapecoil.phases.coiling import CoilingProblem

    cfg = Config()
    cfg.tape.L = 0.1
    cfg.mesh.preset = "coarse"
    cfg.solver.petsc_options = {"snes_max_it": 9, "ksp_type": "gmres"}
    cfg.coiling.petsc_options = {"snes_max_it": 4}
    snes = CoilingProblem(cfg, MPI.COMM_WORLD).solver.snes
    assert snes.getTolerances()[3] == 4  # the phase's table over [solver]'s
    assert snes.getKSP().getType() == "gmres"  # [solver]'s where the phase's says nothing
