"""A tape spring's moment-rotation curve (verification/moment_rotation.py, ``tapecoil fold``,
``tapecoil verify tape-moment-rotation``): the moment against beam theory where the tape is
still straight, the short curve's fold moment, snap and limit point, its files, and bad input
refused before anything is computed."""

import csv
import math

import pytest
from mpi4py import MPI

from tapecoil import theory as th
from tapecoil.app.cli import main


def test_moment_of_a_slightly_bent_tape_is_the_beam_moment(cfg):
    """At a small end rotation the tape bends as a beam of its arc section: M = E I phi / L,
    E the wall's axial modulus, I the arc's (theory.arc_second_moment), within 3 % as the tape's
    linear end moment (verify tape-linear). The moment is dE/dphi of the half tape, doubled."""
    from tapecoil.verification.moment_rotation import BentTape, fold_resolution

    tp, length, phi = cfg.tape, 0.15, 2e-4
    tape = BentTape(
        cfg, "opposite", fold_resolution("coarse", tp.R, length), length, MPI.COMM_WORLD, "test_mr"
    )
    try:
        tape.set_angle(phi)
        assert tape.solver.solve().converged
        moment = tape.moment()
    finally:
        tape.destroy()
    beam = cfg.wall.axial_modulus * th.arc_second_moment(tp.R, tp.alpha, tp.h) * phi / length
    assert moment == pytest.approx(beam, rel=0.03)


@pytest.mark.slow
def test_short_curve_folds_at_the_fold_moment_through_its_snap(cfg):
    """Opposite sense on a piece of 12 R, to 0.6 rad (coarse; further on, the fold's moment
    rises as its transitions near the ends of so short a piece): the primary branch to its first
    critical point, the eigenvalue through zero there and where the fold vanishes (below 1e-4
    of its value at rest, as the case checks); the fold's steady moment within 3 % of the
    moment with the free edges' layers (theory.fold_moment_with_edges); the peak moment and
    the snap on the primary branch, the fold branch stable and far below the peak."""
    from tapecoil.verification.moment_rotation import fold_resolution, moment_rotation_curve

    tp = cfg.tape
    length = 12 * tp.R
    c = moment_rotation_curve(cfg, "opposite", fold_resolution("coarse", tp.R, length), length, 0.6)
    edges = th.fold_moment_with_edges(cfg.wall.bending, cfg.wall.axial_stiffness, tp.alpha, tp.R)
    assert c["steady_fold_moment"] == pytest.approx(edges, rel=0.03)
    assert abs(c["snap_eigenvalue_over_rest"]) < 1e-4
    assert abs(c["fold_vanishes_eigenvalue_over_rest"]) < 1e-4
    assert c["fold_vanishes_rotation"] < c["snap_rotation"]
    assert c["peak_rotation"] <= c["snap_rotation"] and c["peak_moment"] > 10 * c["steady_fold_moment"]
    fold = [r for r in c["rows"] if r[0] == "fold"]
    assert all(r[3] for r in fold) and max(r[2] for r in fold) < 0.1 * c["peak_moment"]
    primary = [r for r in c["rows"] if r[0] == "primary"]
    assert all(r[3] for r in primary[:-1])  # stable up to the snap


@pytest.mark.mpi
def test_primary_branch_on_two_ranks_as_on_one(cfg):
    """The primary branch to its first critical point on two ranks against one: the same
    points and the same snap rotation, to the Newton tolerance."""
    from tapecoil.core.arclength import ArcLength, ArcLengthSettings
    from tapecoil.core.path_system import SolverSystem
    from tapecoil.core.stability import StabilityAnalysis
    from tapecoil.verification.moment_rotation import BentTape, fold_resolution

    tp = cfg.tape
    length = 10 * tp.R

    def primary(comm, name):
        tape = BentTape(cfg, "opposite", fold_resolution("coarse", tp.R, length), length, comm, name)
        path = ArcLength(
            SolverSystem(tape.solver, tape.set_angle),
            ArcLengthSettings(first_step=2e-3, max_step=10.0, min_step=1e-6),
            stability=StabilityAnalysis(3, prefix=f"{name}_stab_"),
        )
        try:
            path.run(0.0, 1.0, until_critical=True)
            return [p.load for p in path.points], path.critical[0].load
        finally:
            path.destroy()
            tape.destroy()

    both, snap_both = primary(MPI.COMM_WORLD, "test_mr_two")
    alone, snap_alone = primary(MPI.COMM_SELF, "test_mr_one")
    assert len(both) == len(alone)
    assert both == pytest.approx(alone, rel=1e-6, abs=1e-9)
    assert snap_both == pytest.approx(snap_alone, rel=1e-6)


def test_bad_input_is_refused_before_computing(cfg):
    from tapecoil.verification.moment_rotation import BentTape, moment_rotation_curve

    res = None  # never reached: refused before a mesh is made
    with pytest.raises(ValueError, match="end angle"):
        moment_rotation_curve(cfg, "opposite", res, 0.1, end_angle=4.0)
    with pytest.raises(ValueError, match="end angle"):
        moment_rotation_curve(cfg, "opposite", res, 0.1, end_angle=-0.5)
    with pytest.raises(ValueError, match="first step"):
        moment_rotation_curve(cfg, "opposite", res, 0.1, end_angle=1.0, first_step=0.0)
    with pytest.raises(ValueError, match="sense"):
        BentTape(cfg, "sideways", res, 0.1)
    with pytest.raises(ValueError, match="length"):
        BentTape(cfg, "opposite", res, 2 * cfg.tape.L)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--angle", "3.5"], "--angle 3.5 rad"),
        (["--angle", "0"], "--angle 0"),
        (["--length", "-1"], "--length -1"),
    ],
)
def test_fold_command_refuses_bad_input_before_computing(tmp_path, capsys, args, message):
    assert main(["fold", "--out", str(tmp_path / "fold"), *args]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "fold").exists()


def test_curve_files_hold_every_state(tmp_path):
    """moment_rotation.csv has a row per state of each sense with its branch and stability, the
    plot is written; the roof's likewise."""
    from tapecoil.post.paths import moment_rotation_files, roof_files

    rows = [
        ("primary", 0.0, 0.0, True, 1.0),
        ("primary", 0.1, 1.0, False, -1.0),
        ("fold", 0.2, 0.04, True, 0.5),
    ]
    curve = {
        "rows": rows,
        "critical": [{"kind": "bifurcation", "rotation": 0.1, "moment": 1.0}],
        "fold_moment_reference": 0.04,
    }
    files = moment_rotation_files({"opposite": curve, "equal": curve}, tmp_path)
    with files[0].open() as f:
        read = list(csv.DictReader(f))
    assert len(read) == 6 and {r["sense"] for r in read} == {"opposite", "equal"}
    assert [r["stable"] for r in read[:3]] == ["1", "0", "1"]
    assert float(read[2]["moment_over_fold_moment"]) == pytest.approx(1.0)
    assert files[1].stat().st_size > 10_000
    roof = {"curve": [(0.0, 0.0, True, 1.0), (10.0, 5.0, False, -1.0)], "critical": [], "mesh": "2 x 2"}
    csv_path, png = roof_files("roof-snap-through", roof, (2226.3, 11.293), tmp_path)
    with csv_path.open() as f:
        assert [r["stable"] for r in csv.DictReader(f)] == ["1", "0"]
    assert png.stat().st_size > 10_000
    assert math.isfinite(float(read[1]["eigenvalue"]))
