"""Validation of the coiling run against physics.md (slow: make validate, under mpirun -n 2).

The benchmark tape on the coarse mesh, flattened and coiled by the full 36 rad with the 1 N
pull. Tolerances (each measure carries its reason): stored energy 5 %, curvature 5 %, surface
stresses 10 % (the thesis reached 17 %), coil radius 2 %, turn separation 10 %.
"""

import dataclasses
import json
import math

import pytest
from mpi4py import MPI

pytestmark = [pytest.mark.slow, pytest.mark.mpi]


@pytest.fixture(scope="module")
def stowed():
    from tapecoil.config import load_config
    from tapecoil.phases.coiling_run import run_coiling

    config = load_config()
    config = dataclasses.replace(config, mesh=dataclasses.replace(config.mesh, preset="coarse"))
    summary, model = run_coiling(config, "results/validate-coil-coarse", MPI.COMM_WORLD, progress=False)
    if MPI.COMM_WORLD.rank == 0:
        print(
            json.dumps(
                {k: v for k, v in summary["measures"].items() if k != "profile"}, indent=1, default=str
            )
        )
    return summary, model


def test_full_coiling_completes(stowed):
    summary, _ = stowed
    assert summary["completed"], summary["message"]
    assert summary["hub_angle"] == pytest.approx(36.0)
    # no turn sinks into the one beneath by more than half a thickness anywhere, at any step
    assert summary["run"]["max_penetration"] < 0.5e-4


def test_stored_energy_of_the_coiled_length(stowed):
    m = stowed[0]["measures"]
    assert m["coiled_length"] == pytest.approx(0.469, rel=0.01)
    assert m["stored_energy_coiled"]["error"] < 0.05


def test_coiled_part_curvature_and_stresses(stowed):
    m = stowed[0]["measures"]
    assert m["cells_interior"] > 20
    assert m["curvature_longitudinal"]["error"] < 0.05
    assert m["curvature_transverse"]["computed"] < 0.1  # the section is flat: |kappa_t| R << 1
    assert m["stress_x"]["error"] < 0.10 and abs(m["stress_x"]["worst"] - 1) < 0.10
    assert m["stress_y"]["error"] < 0.10 and abs(m["stress_y"]["worst"] - 1) < 0.10


def test_coil_radius_and_turn_separation(stowed):
    m = stowed[0]["measures"]
    assert m["outer_radius"]["error"] < 0.02
    assert len(m["turn_radii"]) == 6  # 5.7 turns: six half-turn probes
    assert m["turn_separation"]["error"] < 0.10


def test_ploy_length_is_measured_one_turn_in(stowed):
    """The ploy region one turn in against Eq. 3.5 (physics brief Sec. 7), L_p = w^2 /
    (sqrt(70) beta^(1/4) sqrt(R h)), whose prefactor is uncertain: read with the projected
    width w = 2 R sin(alpha/2) and with the arc width w = b.

    The measure is the distance between two cell midpoints on the centre line (where the
    transverse curvature passes 0.1/R and 0.9/R), so each end is placed only to within an
    element: on this mesh it is known to two element lengths. Held to the projected width's
    reading within that, and short of the arc width's by more than that: the transition is as
    long as Eq. 3.5 says with the section's projected width.
    """
    from tapecoil import theory

    summary, model = stowed
    ploy = summary["measures"]["ploy_length_one_turn"]
    assert ploy["hub_angle"] == pytest.approx(2 * math.pi)
    tp, beta = model.config.tape, model.config.wall.bending.beta
    projected = theory.ploy_length(2 * tp.R * math.sin(tp.alpha / 2), tp.R, tp.h, beta)
    arc = theory.ploy_length(tp.b, tp.R, tp.h, beta)
    assert ploy["reference_projected_width"] == pytest.approx(projected)
    assert ploy["reference_arc_width"] == pytest.approx(arc)
    resolution = 2 * max(model.strip.resolution.element_lengths(tp.L))
    assert ploy["computed"] is not None and 0 < ploy["computed"] < ploy["free_length"]
    assert abs(ploy["computed"] - projected) < resolution, (ploy["computed"], projected, resolution)
    assert ploy["computed"] < arc - resolution, (ploy["computed"], arc, resolution)


def test_coiling_tension_against_eq_2_6():
    """Steady coiling tension on hubs r_c/R = 0.5 ... 0.9 (default mesh, 0.2 m pieces coiled
    5.5 rad): T - N at the root's clamp against Eq. 2.6, and the coil's own steady stretch
    against the plate with its free edges' layers (docs/notes/regimes.md: 0.05 to 0.37 % in energy,
    2 to 3 % in the edges' lift)."""
    from tapecoil.config import load_config
    from tapecoil.phases.tension_study import coiling_tension_study

    study = coiling_tension_study(load_config(), comm=MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        print(json.dumps(study, indent=1))
    assert [case["ratio"] for case in study] == [0.5, 0.6, 0.7, 0.8, 0.9]
    for case in study:
        # the root's clamp holds the whole width flat, as the plate law assumes, so its mean
        # reading follows Eq. 2.6 closely on every hub; the margin above what these hubs measure
        # is for the mean over a window that holds only a few periods of the oscillation as
        # nodes pass the lift-off point (its remainder moves the mean)
        assert case["error"] < 0.03, case
        assert case["max_penetration"] < 0.5e-4, case
        assert case["coil_energy_per_length"] == pytest.approx(case["edge_layer_energy_per_length"], rel=0.01)
        assert case["edge_rise"] == pytest.approx(case["edge_rise_theory"], rel=0.05)


def assert_coiled_to_36_rad(summary: dict) -> None:
    """The full benchmark coil against physics.md with the spiral run's tolerances."""
    assert summary["completed"], summary["message"]
    assert summary["hub_angle"] == pytest.approx(36.0)
    m = summary["measures"]
    assert m["stored_energy_coiled"]["error"] < 0.05
    assert m["curvature_longitudinal"]["error"] < 0.05
    assert m["stress_x"]["error"] < 0.10 and m["stress_y"]["error"] < 0.10
    assert m["outer_radius"]["error"] < 0.02 and m["turn_separation"]["error"] < 0.10


def test_equal_sense_benchmark_against_its_plate_estimate():
    """The benchmark coiled in equal sense to 36 rad on the default mesh (the coarse one stops
    at 33.9 rad: docs/notes/coiling.md), against the equal-sense plate estimate of physics.md Sec. 10
    with the opposite sense's tolerances. Measured: energy -0.87 %, curvature 0.35 %, stresses
    0.70 % and 0.69 %, outer radius 0.24 %. The section's edges start 9.3 mm inside the hub, so
    the flattening runs without the penetration stop."""
    from tapecoil.config import load_config
    from tapecoil.phases.coiling_run import run_coiling

    config = load_config()
    config = dataclasses.replace(
        config,
        coiling=dataclasses.replace(config.coiling, sense="equal"),
        contact=dataclasses.replace(config.contact, stop_penetration=100.0),
    )
    summary, _ = run_coiling(config, "results/validate-coil-equal-default", MPI.COMM_WORLD, progress=False)
    assert_coiled_to_36_rad(summary)


def test_benchmark_coils_on_its_own_turns():
    """The benchmark on the coarse mesh with the contact of the real surfaces (no spiral
    obstacle): where the turns lie is a prediction. Against physics.md with the spiral run's
    tolerances, and the separation of distinct turns read from the surface snapshots alone
    (independent of the contact code) at least 0.6 h at every step (the spiral run's: 0.46 h).
    Measured (2 ranks, 5 to 12.5 min): energy -2.8 %, outer radius +0.72 %, turn separation
    1.001 h, closest turns 0.64 to 0.73 h, hub torque's two readings 0.2 to 0.3 % apart. The
    interlayer pressure by the statics of a coil of rings: each inner turn's jump against its
    axial force (0.968, 1.007, 0.977; tolerance 5 %), the hub's push against the integral of N
    over the pressed tape (0.993; tolerance 1 %)."""
    from tapecoil.app import results
    from tapecoil.config import load_config
    from tapecoil.measures.separation import separation_measure
    from tapecoil.phases.coiling_run import run_coiling

    config = load_config()
    config = dataclasses.replace(
        config,
        mesh=dataclasses.replace(config.mesh, preset="coarse"),
        contact=dataclasses.replace(config.contact, turns="surface"),
    )
    # with its config.toml, from which the separation measure places the hub, as a run's
    directory = results.prepare_directory("results/validate-coil-surface-coarse", config, MPI.COMM_WORLD)
    summary, _ = run_coiling(config, directory, MPI.COMM_WORLD, progress=False)
    assert_coiled_to_36_rad(summary)
    assert summary["measures"]["hub_torque"]["error"] < 0.03
    assert summary["measures"]["pressure_jump"]["passed"], summary["measures"]["pressure_jump"]
    assert summary["measures"]["hub_reaction"]["passed"], summary["measures"]["hub_reaction"]
    closest = separation_measure(directory, "coiling", MPI.COMM_WORLD)
    assert closest["computed"] > 0.6, closest
