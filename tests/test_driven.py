"""A tape on its hub driven in time (tapecoil.phases.driven): slow enough, the quasi-static path."""

import dataclasses

import pytest
from mpi4py import MPI

from tapecoil.config import CoilingConfig, Config, TapeConfig

ANGLE = 0.5  # [rad] the hub turns
SPEED = 0.1  # [m/s] tape speed: the pull's inertial part rho_l v^2 is 1e-4 of it


def short_tape() -> Config:
    cfg = Config()
    return dataclasses.replace(
        cfg,
        tape=dataclasses.replace(TapeConfig(), L=0.12),
        coiling=dataclasses.replace(CoilingConfig(), hub_angle=ANGLE),
        mesh=dataclasses.replace(cfg.mesh, preset="coarse"),
    )


def driven_coil(comm, dt=1e-3):
    """Flattened quasi-statically, then the hub turned by ANGLE at the tape speed SPEED, eased in
    and out (a smoothstep in time), then held still as long again."""
    from tapecoil.core.smoothing import smoothstep
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun
    from tapecoil.phases.driven import DrivenMotion

    model = CoilingProblem(short_tape(), comm)
    CoilingRun(model).flatten()
    motion = DrivenMotion(model)
    rho = model.tape.r_hub + model.config.tape.h / 2
    duration = 1.5 * ANGLE * rho / SPEED  # the smoothstep's peak speed is 1.5 times its mean

    def turn(t):
        model.set_hub_angle(ANGLE * float(smoothstep(t / duration)))

    motion.run(2 * duration, turn, dt)
    return model, motion


def test_a_slow_drive_follows_the_quasi_static_coiling():
    """The hub turned slowly in time comes to the state the load-stepped coiling reaches at the
    same angle, and rests there (measured: energy and slide to 1e-8, root force to 6e-7, kinetic
    energy 2e-16 of the strain energy, 192 steps): the inertia, the drive and the pull's dead load
    are those of the static problem in the limit."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    static = CoilingProblem(short_tape(), MPI.COMM_SELF)
    run = CoilingRun(static)
    run.flatten()
    run.coil(ANGLE)
    driven, motion = driven_coil(MPI.COMM_SELF)
    assert driven.root.angle == pytest.approx(ANGLE, abs=1e-12)
    energy = (driven.tape.energies()["strain"], static.tape.energies()["strain"])
    assert energy[0] == pytest.approx(energy[1], rel=1e-5)
    assert driven.end_slide() == pytest.approx(static.end_slide(), rel=1e-5)
    forces = (driven.edge_forces()["root_tension"], static.edge_forces()["root_tension"])
    assert forces[0] == pytest.approx(forces[1], rel=1e-3)
    assert motion.kinetic_energy() < 1e-7 * energy[1]


def test_a_driven_motion_refuses_an_undamped_scheme():
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.driven import DrivenMotion

    with pytest.raises(ValueError, match="rho_inf"):
        DrivenMotion(CoilingProblem(short_tape(), MPI.COMM_SELF), rho_inf=1.0)


@pytest.mark.mpi
def test_two_ranks_drive_the_tape_as_one():
    assert MPI.COMM_WORLD.size > 1
    parallel, p_motion = driven_coil(MPI.COMM_WORLD)
    serial, s_motion = driven_coil(MPI.COMM_SELF)
    assert p_motion.steps == s_motion.steps
    assert parallel.tape.energies()["strain"] == pytest.approx(serial.tape.energies()["strain"], rel=1e-6)
    assert parallel.end_slide() == pytest.approx(serial.end_slide(), rel=1e-6)
