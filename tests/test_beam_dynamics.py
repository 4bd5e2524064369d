"""The geometrically exact beam in time (tapecoil.models.beam_dynamics): its inertia and
generalized-alpha steps, against Euler-Bernoulli's cantilever and the conservation laws of a
free body."""

import math

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.models.beam_dynamics import BeamDynamics
from tapecoil.models.beam_problem import BeamProblem
from tapecoil.models.beam_section import BeamSection
from tapecoil.verification.beam import fixed_frame, straight_line
from tapecoil.verification.hybrid_motion import cantilever_period, crossing_period

# a steel strip 20 mm wide and 2 mm deep, 1 m long: slender (L / depth = 500), so that shear
# and rotary inertia move its first frequency by about (depth / L)^2, far below the tolerances
E, NU, DENSITY, WIDTH, DEPTH, LENGTH = 200e9, 0.3, 7800.0, 0.02, 0.002, 1.0
AREA = WIDTH * DEPTH
I2, I3 = WIDTH * DEPTH**3 / 12, DEPTH * WIDTH**3 / 12


def strip(comm, name: str, elements: int = 16) -> tuple[BeamProblem, BeamSection]:
    section = BeamSection.rectangle(E, NU, WIDTH, DEPTH)
    return BeamProblem(straight_line, LENGTH, elements, section, fixed_frame, comm=comm, name=name), section


def dynamics(problem: BeamProblem, rho_inf: float = 1.0) -> BeamDynamics:
    return BeamDynamics(problem, DENSITY * AREA, DENSITY * np.array([I2 + I3, I2, I3]), rho_inf=rho_inf)


def cantilever_vibration(comm, periods: float = 3.0, per_period: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """A cantilever let go from the static deflection of a tip force (1 mm at the tip): the
    times [s] and tip deflections [m] of ``per_period`` steps per Euler-Bernoulli period."""
    problem, section = strip(comm, "vibrating")
    problem.clamp((0, 0, 0))
    problem.end_load((LENGTH, 0, 0), force=(0, 0, 3 * section.EI2 * 1e-3 / LENGTH**3))
    problem.solve(1.0, first_step=1.0, max_step=1.0)
    problem.load.value = 0.0  # let go
    beam = dynamics(problem)
    dt = euler_bernoulli_period() / per_period
    times, tips = [], []
    for _ in range(int(periods * per_period)):
        assert beam.step(dt).converged
        times.append(beam.time)
        tips.append(problem.position((LENGTH, 0, 0))[2])
    return np.array(times), np.array(tips)


def euler_bernoulli_period() -> float:
    """The strip's first period as a cantilever by Euler-Bernoulli."""
    return cantilever_period(E * I2, DENSITY * AREA, LENGTH)


def test_a_cantilever_swings_at_euler_bernoullis_first_frequency():
    """Let go from a tip deflection of 1 mm (a thousandth of the length: linear): the period
    between zero crossings within 1e-3 of Euler-Bernoulli's first mode (measured 3e-5), the
    trapezoidal rule at 100 steps per period lengthening it by (omega dt)^2 / 12 = 3.3e-4 at
    most; and no amplitude lost (rho_inf = 1), the last period's within 1 % of the start's."""
    times, tips = cantilever_vibration(MPI.COMM_WORLD)
    period = crossing_period(times, tips)
    assert period == pytest.approx(euler_bernoulli_period(), rel=1e-3)
    assert np.abs(tips[-100:]).max() == pytest.approx(1e-3, rel=1e-2)


def free_spin(comm, step_angle: float, turn: float = math.pi) -> dict:
    """A free strip spun about an oblique axis through its middle (rigid at the start, no
    support, no load) by ``turn`` [rad] in steps of ``step_angle`` [rad], trapezoidal rule:
    the largest drift of its energy (kinetic + strain) and of its momenta (each relative to the
    largest at the start), read from the velocities."""
    problem, _ = strip(comm, "spinning")
    beam = dynamics(problem)
    rate = 10.0 * np.ones(3) / math.sqrt(3.0)  # rad/s
    middle = np.array([LENGTH / 2, 0.0, 0.0])

    def velocity(x):
        spin = np.broadcast_to(rate, (x.shape[1], 3))
        return np.vstack([np.cross(spin, (x - middle[:, None]).T).T, spin.T])

    beam.set_velocity(velocity)
    momenta, energy = beam.momenta(), beam.kinetic_energy()
    drift = {"energy": 0.0, "momenta": 0.0}
    dt = step_angle / float(np.linalg.norm(rate))
    for _ in range(round(turn / step_angle)):
        assert beam.step(dt).converged
        now = beam.kinetic_energy() + problem.model.strain_energy()
        drift["energy"] = max(drift["energy"], abs(now - energy) / energy)
        drift["momenta"] = max(
            drift["momenta"], float(np.abs(beam.momenta() - momenta).max() / np.abs(momenta).max())
        )
    return drift


def test_a_free_spinning_strip_keeps_its_energy_and_momenta_to_second_order():
    """Half a turn about an oblique axis (gyroscopic: the strip's moments of inertia differ by
    its aspect ratio): in steps of 0.05 rad the energy drifts by less than 4e-3 and the momenta
    by less than 2e-3 (measured 1.7e-3 and 8.3e-4: the scheme integrates the rotation vector of
    each step as a vector, exact to first order in the step's turn); halving the step divides
    both drifts by at least 3.5 (measured 4.0), the scheme's second order."""
    coarse, fine = (free_spin(MPI.COMM_WORLD, step) for step in (0.05, 0.025))
    assert coarse["energy"] < 4e-3 and coarse["momenta"] < 2e-3
    for key in coarse:
        assert coarse[key] / fine[key] > 3.5, (key, coarse[key], fine[key])


def test_bad_inertia_is_refused():
    problem, _ = strip(MPI.COMM_SELF, "refused", elements=2)
    with pytest.raises(ValueError, match="line density"):
        BeamDynamics(problem, 0.0, (1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="rotary inertia"):
        BeamDynamics(problem, 1.0, (1.0, 0.0, 1.0))


@pytest.mark.mpi
def test_two_ranks_swing_the_cantilever_as_one():
    """The cantilever's tip over a period on 2 ranks and on one: the same to 1e-12 m."""
    assert MPI.COMM_WORLD.size > 1
    _, two = cantilever_vibration(MPI.COMM_WORLD, periods=1.0, per_period=40)
    _, one = cantilever_vibration(MPI.COMM_SELF, periods=1.0, per_period=40)
    assert np.abs(two - one).max() < 1e-12


def test_a_beam_with_gravity_and_one_without_share_their_compiled_forms():
    """Gravity enters the equations of motion as a Constant whatever its value: a run under
    gravity (a ground test) and one in orbit compile the same residual, Jacobian and reaction
    (a term of the residual written only under gravity gave the Jacobian, derived from it, a
    signature of its own too)."""
    forms = []
    for gravity in ((0.0, 0.0, 0.0), (0.0, -9.81, 0.0)):
        problem, _ = strip(MPI.COMM_SELF, "weighed", elements=2)
        motion = BeamDynamics(problem, DENSITY * AREA, (1.0, 1.0, 1.0), gravity=gravity)
        forms.append([form.signature() for form in (*motion.forms, motion.reaction_form, motion.weight_work)])
    assert forms[0] == forms[1]
