"""Shell problems stated as a benchmark is: supports, loads per unit load parameter, steps in its units."""

import math

import pytest
from mpi4py import MPI

from tapecoil.geometry.meshes import MeshResolution
from tapecoil.geometry.surfaces import MappedSurface, StripGeometry
from tapecoil.models.problem import ShellProblem
from tapecoil.models.shell import ShellMaterial

# the pinched semicylinder of Sze, Liu and Lo (2004)
R, L, h, E, nu, P = 1.016, 3.048, 0.03, 2.0685e7, 0.3, 2000.0


def pinched(problem: ShellProblem, force: float) -> float:
    problem.clamp("xi1_min")
    problem.point_force((L, 0.0), force=(0.0, 0.0, 1.0))
    problem.solve(force, first_step=0.1 * force, max_step=0.2 * force)
    return problem.displacement_at((L, 0.0))[2]


def test_a_symmetry_plane_makes_half_the_shell_behave_as_the_whole():
    """The pinched semicylinder against its half cut at the crown's plane (y = 0), half the force.

    The whole shell, loaded and supported symmetrically, deforms symmetrically, so its half with
    the symmetry plane's conditions (u_y = 0, the director in the plane) must give the same
    deflection on the mirrored mesh, to the solver's tolerance. The half's other straight edge
    lies on the plane z = R, as the whole's two do.
    """
    material = ShellMaterial(E, nu, h)
    whole = ShellProblem(StripGeometry(R, math.pi * R, L), MeshResolution(8, 8), material)
    for side in ("xi2_min", "xi2_max"):
        whole.symmetry_plane(side, normal=(0, 0, 1))
    w_whole = pinched(whole, P)

    half_surface = MappedSurface(
        lambda xi, ops: (xi[0], R * ops.sin(xi[1] / R), R * (1 - ops.cos(xi[1] / R))),
        ((0.0, L), (0.0, math.pi * R / 2)),
    )
    half = ShellProblem(half_surface, MeshResolution(4, 8), material)
    half.symmetry_plane("xi2_min", normal=(0, -1, 0))
    half.symmetry_plane("xi2_max", normal=(0, 0, 1))
    w_half = pinched(half, P / 2)
    assert w_whole == pytest.approx(1.7, rel=0.05)  # the nonlinear range: Sze's 1.715 on this mesh
    assert w_half == pytest.approx(w_whole, rel=1e-9)


def test_a_fixed_point_props_a_cantilever():
    """A strip clamped at one end and propped at the other (its centre held in z, a roller),
    a small force at mid-span: the deflection under it is 7 P L^3 / (768 E I) (Roark, the
    propped cantilever), within 1 % (shear and the plate's width effect are below that for nu = 0
    and L / h = 100)."""
    length, width, thickness, modulus = 10.0, 1.0, 0.1, 1.2e6
    problem = ShellProblem(
        StripGeometry(math.inf, width, length), MeshResolution(1, 16), ShellMaterial(modulus, 0.0, thickness)
    )
    problem.clamp("xi1_min")
    problem.fix_point((length, 0.0), "z")
    force = 1e-4  # a deflection of 1e-4 L: linear
    problem.point_force((length / 2, 0.0), force=(0.0, 0.0, -1.0))
    problem.solve(force, first_step=force, max_step=force)
    inertia = width * thickness**3 / 12
    exact = 7 * force * length**3 / (768 * modulus * inertia)
    assert -problem.displacement_at((length / 2, 0.0))[2] == pytest.approx(exact, rel=0.01)
    assert abs(problem.displacement_at((length, 0.0))[2]) < 1e-12  # the prop holds


def test_the_newton_count_includes_the_attempts_that_were_cut_back():
    """A strip rolled by an end moment in one step of a quarter turn, with so few Newton
    iterations allowed that the step fails and is cut back: each step's record counts the
    failed attempt's iterations in its total, and the problem's count is the sum of all of them,
    none lost when the solver is destroyed."""
    from tapecoil.config import SolverConfig

    length, width, thickness, modulus = 12.0, 1.0, 0.1, 1.2e6
    problem = ShellProblem(
        StripGeometry(math.inf, width, length), MeshResolution(1, 8), ShellMaterial(modulus, 0.0, thickness)
    )
    problem.clamp("xi1_min")
    problem.edge_moment("xi1_max", moment=1 / width)
    quarter = 2 * math.pi * modulus * (width * thickness**3 / 12) / length / 4
    history = problem.solve(
        quarter, first_step=quarter, max_step=quarter, solver_config=SolverConfig(max_newton=4)
    )
    cut = [r for r in history if r.cutbacks > 0]
    assert cut, [(r.load, r.iterations) for r in history]
    for r in cut:
        assert r.attempts == r.cutbacks + 1
        assert r.total_iterations > r.iterations
    assert all(r.total_iterations == r.iterations for r in history if r.attempts == 1)
    assert problem.newton_iterations == sum(r.total_iterations for r in history)
    assert problem.newton_iterations > sum(r.iterations for r in history)


SCRIPT = """
import math
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.problem import ShellProblem
from tapecoil.models.shell import ShellMaterial

strip = StripGeometry(math.inf, 1.0, 10.0)
problem = ShellProblem(strip, MeshResolution(1, 4), ShellMaterial(1.2e6, 0.0, 0.1))
problem.clamp("xi1_min")
problem.point_force((10.0, 0.0), force=(0.0, 0.0, 1.0))
problem.solve(1e-4, first_step=1e-4, max_step=1e-4)
"""


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="starts its own process")
def test_a_users_script_takes_petsc_options_from_its_command_line(tmp_path):
    """``python3 my_script.py -shell_snes_monitor``: PETSc's monitor of the problem's solver
    prints, as the ``tapecoil`` command's options do (a fresh process, as a user runs it)."""
    import subprocess
    import sys
    from pathlib import Path

    script = tmp_path / "my_script.py"
    script.write_text(SCRIPT)
    root = Path(__file__).parents[1]
    plain = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, cwd=root)
    assert plain.returncode == 0, plain.stderr
    assert "SNES Function norm" not in plain.stdout
    run = subprocess.run(
        [sys.executable, str(script), "-shell_snes_monitor"], capture_output=True, text=True, cwd=root
    )
    assert run.returncode == 0, run.stderr
    assert "SNES Function norm" in run.stdout


@pytest.fixture(scope="module")
def flat():
    return ShellProblem(StripGeometry(math.inf, 1.0, 4.0), MeshResolution(1, 4), ShellMaterial(1e6, 0.0, 0.1))


@pytest.mark.parametrize(
    "statement, message",
    [
        (lambda p: p.clamp("root"), "edge 'root': one of xi1_min"),
        (lambda p: p.symmetry_plane("xi1_max", normal=(1, 1, 0)), "must be"),
        (lambda p: p.symmetry_plane("xi1_max", normal=(0, 1, 0)), "not in a plane normal to y"),
        (lambda p: p.symmetry_plane("xi2_min", normal=(0, 0, 1)), "must contain the shell's normal"),
        (lambda p: p.fix_point((0.3, 0.1), "z"), "no mesh node"),
        (lambda p: p.fix_point((4.0, 0.0), "w"), "x, y and z"),
        (lambda p: p.point_force((1.1, 0.0), (0, 0, 1)), "no mesh node"),
        (lambda p: p.edge_moment("xi1_max", 1.0, angle=2), "0 or 1"),
        (lambda p: p.solve(1.0, first_step=0.5, max_step=0.2), "first_step"),
        (lambda p: p.solve(-1.0, first_step=0.1, max_step=0.2), "positive"),
    ],
)
def test_a_misstated_problem_is_refused_before_solving(flat, statement, message):
    with pytest.raises(ValueError, match=message):
        statement(flat)


def test_a_valid_symmetry_plane_of_a_strip_is_accepted(flat):
    """The plane x = 4 through the free end contains the end and the normal: accepted (theta_1)."""
    count = len(flat.bcs)
    flat.symmetry_plane("xi1_max", normal=(1, 0, 0))
    assert len(flat.bcs) == count + 2
    assert MPI.COMM_WORLD.allreduce(len(flat.bcs)) == MPI.COMM_WORLD.size * (count + 2)
