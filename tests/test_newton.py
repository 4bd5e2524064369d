"""The SNES wrapper: its PETSc options (caller-named prefixes, precedence, no leaks, the command
line) and its terms' applied Jacobian parts."""

import json
import subprocess
import sys
from pathlib import Path

import dolfinx
import pytest
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil.config import SolverConfig
from tapecoil.core.newton import SNESSolver


def toy_problem():
    """-div grad u + u^3 = 1 on the unit square, u = 0 on the boundary: Newton in a few steps."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 6, 6)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
    u = dolfinx.fem.Function(V)
    v = ufl.TestFunction(V)
    F = (ufl.inner(ufl.grad(u), ufl.grad(v)) + u**3 * v - v) * ufl.dx
    J = ufl.derivative(F, u, ufl.TrialFunction(V))
    mesh.topology.create_connectivity(1, 2)
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    bc = dolfinx.fem.dirichletbc(0.0, dolfinx.fem.locate_dofs_topological(V, 1, facets), V)
    return F, J, u, [bc]


def solver(prefix, settings=None, **kw):
    F, J, u, bcs = toy_problem()
    return SNESSolver.from_config(F, J, u, bcs, settings or SolverConfig(), prefix=prefix, **kw)


def held(prefix):
    """The keys under ``prefix`` in PETSc's global options database."""
    return {k for k in PETSc.Options().getAll() if k.startswith(prefix)}


@pytest.fixture
def user_options():
    """Options put into the database as the command line would; removed after the test."""
    opts, names = PETSc.Options(), []

    def put(name, value):
        opts[name] = value
        names.append(name)

    yield put
    for name in names:
        opts.delValue(name)


def test_the_prefix_is_the_callers_and_checked():
    s = solver("toy_")
    assert s.snes.getOptionsPrefix() == "toy_"
    assert s.solve().converged
    s.destroy()
    F, J, u, bcs = toy_problem()
    for bad in ("", "toy", "1toy_", "-toy_", "to y_"):
        with pytest.raises(ValueError, match="options prefix"):
            SNESSolver(F, J, u, bcs, prefix=bad)


def test_the_database_wins_over_every_table_and_nothing_is_left_behind(user_options):
    user_options("toy_snes_rtol", 1e-3)  # the user's, e.g. -toy_snes_rtol 1e-3
    settings = SolverConfig(
        rtol=1e-9, max_newton=40, petsc_options={"snes_rtol": 1e-6, "snes_max_it": 7, "ksp_type": "gmres"}
    )
    s = solver("toy_", settings, defaults={"ksp_type": "cg"}, options={"ksp_type": "preonly"})
    rtol, _atol, _stol, max_it = s.snes.getTolerances()
    assert rtol == 1e-3  # the database over the [solver] table and over solver.rtol
    assert max_it == 7  # the [solver] table over solver.max_newton
    assert s.snes.getKSP().getType() == "preonly"  # the phase's table over [solver]'s and the caller's
    assert s.solve().converged
    assert held("toy_") == {"toy_snes_rtol"}  # the user's option alone, untouched
    assert PETSc.Options().getReal("toy_snes_rtol") == 1e-3
    s.destroy()


def test_options_do_not_leak_to_the_next_solver():
    first = solver("one_", SolverConfig(petsc_options={"snes_max_it": 3, "snes_type": "ksponly"}))
    assert first.snes.getTolerances()[3] == 3 and first.snes.getType() == "ksponly"
    first.solve()
    other = solver("two_")  # another prefix
    again = solver("one_")  # the same prefix, without the table
    for s in (other, again):
        assert s.snes.getTolerances()[3] == 25 and s.snes.getType() == "newtonls"
    assert held("one_") == held("two_") == set()
    for s in (first, other, again):
        s.destroy()


def test_the_command_line_options_under_a_prefix_are_read_as_petsc_reads_them():
    from tapecoil.core.petsc_options import command_line_options

    argv = ["-v", "-shell_snes_rtol", "1e-3", "-shell_snes_monitor", "-other_ksp_view", "-shell_x", "-1"]
    argv += ["input.toml", "--", "-shell_after_the_end"]
    assert command_line_options("shell_", argv) == {"snes_rtol": "1e-3", "snes_monitor": "", "x": "-1"}
    assert command_line_options("other_", argv) == {"ksp_view": ""}
    assert command_line_options("none_", argv) == {}


def test_a_scripts_own_command_line_reaches_its_solver(monkeypatch):
    """A user's script run as ``python3 script.py -toy_snes_max_it 3`` sets its solver's option,
    over the configuration's table, only while PETSc reads it (nothing is left behind); an
    option a caller put in the database itself wins over the command line."""
    monkeypatch.setattr(sys, "argv", ["script.py", "-toy_snes_max_it", "3", "-toy_snes_type", "ksponly"])
    s = solver("toy_", SolverConfig(petsc_options={"snes_max_it": 7}))
    assert s.snes.getTolerances()[3] == 3 and s.snes.getType() == "ksponly"
    s.destroy()
    assert held("toy_") == set()
    opts = PETSc.Options()
    opts["toy_snes_max_it"] = 5
    try:
        s = solver("toy_")
        assert s.snes.getTolerances()[3] == 5
        s.destroy()
    finally:
        opts.delValue("toy_snes_max_it")


def offset_problem(offset):
    """-div grad u + (u - c)^3 = 1, u = c on the boundary, c = ``offset``: the toy problem's
    solution shifted by c, so that a large state norm sits beside a small correction."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 6, 6)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
    u = dolfinx.fem.Function(V)
    u.x.array[:] = offset
    v = ufl.TestFunction(V)
    F = (ufl.inner(ufl.grad(u), ufl.grad(v)) + (u - offset) ** 3 * v - v) * ufl.dx
    J = ufl.derivative(F, u, ufl.TrialFunction(V))
    mesh.topology.create_connectivity(1, 2)
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    bc = dolfinx.fem.dirichletbc(float(offset), dolfinx.fem.locate_dofs_topological(V, 1, facets), V)
    return F, J, u, [bc]


def test_convergence_is_judged_on_the_residual(user_options):
    """A small Newton step against a large state does not end a solve; the residual does.

    With the state at 1e7 (as director angles of tens of radians dwarf a correction), PETSc's
    step test (stol = 1e-8) ends the first solve after one iteration with the residual far from
    converged. The residual test goes on to rtol, and a solve that starts at the residual's
    round-off floor ends there at once instead of running to max_it.
    """
    settings = SolverConfig(rtol=1e-12, atol=1e-14)
    s = SNESSolver.from_config(*offset_problem(1e7), settings, prefix="toy_")
    assert s.snes.getTolerances()[2] == 0.0
    assert s.snes.getDivergenceTolerance() == 1e4  # PETSc's divergence test, kept
    result = s.solve()
    assert result.converged and result.iterations > 1
    assert result.residual_norm <= max(1e-12 * s.norms[0], s.convergence.floor)
    assert 0 < s.convergence.floor < 1e-4 * s.norms[0]  # eps |x| through J: round-off, not physics
    s_floor = s.convergence.floor
    again = s.solve()  # from the converged state: at the floor from the start
    assert again.converged and again.iterations <= 2 and s.convergence.floor_ends >= 1
    s.destroy()

    user_options("toy_snes_divergence_tolerance", 1e300)
    assert solver("toy_").snes.getDivergenceTolerance() == 1e300  # the user's
    user_options("toy_snes_convergence_test", "default")  # PETSc's own test, on the user's word
    petsc = SNESSolver.from_config(*offset_problem(1e7), settings, prefix="toy_", snes_stol=1e-8)
    first = petsc.solve()
    assert first.reason_name == "CONVERGED_SNORM_RELATIVE" and first.iterations == 1
    assert first.residual_norm > 10 * s_floor
    petsc.destroy()


def test_the_turns_contact_solver_keeps_the_divergence_test():
    """The turns' contact keeps PETSc's divergence test: without it the default-mesh coiling ran
    away, no step converging while the memory filled (docs/notes/coiling.md).
    (An option of -1 would not have switched it off: PETSc 3.22 and 3.25 read -1 as
    PETSC_DETERMINE, the default.)"""
    from tapecoil.contact.term import SOLVER_OPTIONS

    s = SNESSolver.from_config(*offset_problem(1e7), SolverConfig(), prefix="toy_", **SOLVER_OPTIONS)
    assert s.snes.getDivergenceTolerance() == 1e4
    s.destroy()


def test_options_read_at_the_first_solve_reach_mumps(user_options):
    """MUMPS reads its ICNTL options when it factorises, at the first solve, not at setFromOptions."""
    s = solver("toy_", SolverConfig(petsc_options={"mat_mumps_icntl_14": 33, "mat_mumps_icntl_4": 1}))
    assert s.solve().converged
    factor = s.snes.getKSP().getPC().getFactorMatrix()
    assert factor.getMumpsIcntl(14) == 33 and factor.getMumpsIcntl(4) == 1
    s.destroy()
    user_options("toy_mat_mumps_icntl_14", 44)
    s = solver("toy_", SolverConfig(petsc_options={"mat_mumps_icntl_14": 33}))
    assert s.solve().converged
    assert s.snes.getKSP().getPC().getFactorMatrix().getMumpsIcntl(14) == 44
    s.destroy()


def test_petsc_options_are_split_off_the_command_line():
    from tapecoil.app.cli import _known_options, build_parser, split_petsc_options

    known = _known_options(build_parser())
    argv = ["coil", "c.toml", "--out", "x", "-coil_snes_monitor", "--json", "-coil_snes_rtol", "1e-3"]
    argv += ["-deploy_snes_divergence_tolerance", "-1", "-h", "-coil_ksp_view"]
    ours, petsc = split_petsc_options(argv, known)
    assert ours == ["coil", "c.toml", "--out", "x", "--json", "-h"]
    assert petsc == [
        "-coil_snes_monitor",
        "-coil_snes_rtol",
        "1e-3",
        "-deploy_snes_divergence_tolerance",
        "-1",
        "-coil_ksp_view",
    ]
    assert split_petsc_options(["verify", "--", "-x"], known) == (["verify", "--", "-x"], [])


def test_main_hands_petsc_options_over_and_takes_them_back(capsys):
    """In a process where PETSc is loaded, main() puts them in the database for the command only."""
    from tapecoil.app.cli import main

    assert main(["verify", "tape-linear", "--json", "-verify_tape_linear_ksp_converged_reason"]) == 0
    out = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:  # the one that prints
        assert "Linear verify_tape_linear_ solve converged" in out  # PETSc's own report of the KSP
        payload = json.loads(out[out.index("[") :])
        assert payload[0]["passed"] is True
        assert all(c["passed"] is True for c in payload[0]["checks"])  # booleans, not 1.0
    assert held("verify_") == set()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="starts its own process")
def test_coil_command_line_reaches_petsc(tmp_path):
    """tapecoil coil ... -coil_snes_monitor prints PETSc's SNES monitor (a fresh process: PETSc
    reads the options at its initialisation)."""
    config = tmp_path / "short.toml"
    config.write_text("[tape]\nL = 0.1\n[coiling]\nhub_angle = 0.3\n")
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "tapecoil", "coil", str(config), "--mesh", "coarse", "--out", str(out)]
    cmd += ["--no-report", "-coil_snes_monitor"]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=Path(__file__).parents[1])
    assert run.returncode == 0, run.stderr
    assert "SNES Function norm" in run.stdout
    assert (out / "summary.json").is_file()


def test_a_table_value_of_true_is_a_flag():
    """TOML true for a PETSc flag acts as the bare flag would (-toy_snes_ksp_ew)."""
    s = solver("toy_", SolverConfig(petsc_options={"snes_ksp_ew": True}))
    assert s.snes.getUseEW()
    s.destroy()
    assert not solver("toy_").snes.getUseEW()


class MeanCoupling:
    """A solver term with a dense part of the Jacobian it applies instead of assembling: the
    residual gains c * (sum of the free dofs of u) in every free row (its owned dofs ``free``)."""

    def __init__(self, c, free):
        self.c, self.free = c, free
        self.applied = 0

    def begin(self):
        pass

    def _sum(self, vec):
        local = float(vec.getArray(readonly=True)[self.free].sum())
        return vec.getComm().tompi4py().allreduce(local, op=MPI.SUM)

    def add_residual(self, b):
        values = b.getArray()
        values[self.free] += self.c * self._sum(self.u.x.petsc_vec)
        b.setArray(values)

    def add_jacobian(self, A):
        return False

    def apply_coupling(self, x, y):
        self.applied += 1
        values = y.getArray()
        values[self.free] += self.c * self._sum(x)
        y.setArray(values)


def test_a_terms_applied_jacobian_part_enters_newtons_operator():
    """A term's applied part joins the assembled matrix in Newton's operator (GMRES
    preconditioned by the factorised assembled part): Newton converges as with the exact
    Jacobian, in the iterations it takes without the coupling, to the same tolerance."""
    import numpy as np

    F, J, u, bcs = toy_problem()
    n_owned = u.function_space.dofmap.index_map.size_local
    fixed = bcs[0].dof_indices()[0]
    free = np.setdiff1d(np.arange(n_owned), fixed[fixed < n_owned])
    options = {"ksp_type": "gmres", "ksp_rtol": 1e-10}
    reference = SNESSolver.from_config(F, J, u, bcs, SolverConfig(), prefix="uncoupled_", options=options)
    result = reference.solve()
    assert result.converged
    reference.destroy()
    u.x.array[:] = 0.0
    s = SNESSolver.from_config(F, J, u, bcs, SolverConfig(), prefix="coupled_", options=options)
    term = MeanCoupling(0.05, free)
    term.u = u
    s.terms.append(term)
    coupled = s.solve()
    assert coupled.converged and term.applied > 0
    assert coupled.iterations <= result.iterations + 1
    # the solution satisfies the coupled equations: the residual with the term is small
    s._residual(None, s.x, s.b)
    assert s.b.norm() <= 1e-8
    s.destroy()


class FarCoupling:
    """A solver term that couples two distant owned dofs of each rank with a spring of stiffness
    c (a pattern beyond the forms'), assembled; ``renew`` is what its begin() answers."""

    def __init__(self, c, pair):
        self.c, self.pair, self.renew = c, pair, False

    def begin(self):
        return self.renew

    def add_residual(self, b):
        u = self.u.x.array
        i, j = self.pair
        values = b.getArray()
        values[i] += self.c * (u[i] - u[j])
        values[j] -= self.c * (u[i] - u[j])
        b.setArray(values)

    def add_jacobian(self, A):
        import numpy as np

        rows = np.array(A.getOwnershipRange()[0] + np.asarray(self.pair), dtype=PETSc.IntType)
        C = PETSc.Mat().create(A.getComm())
        C.setSizes(A.getSizes())
        C.setType(PETSc.Mat.Type.AIJ)
        C.setPreallocationNNZ((2, 2))
        C.setValues(rows, rows, self.c * np.array([[1.0, -1.0], [-1.0, 1.0]]))
        C.assemble()
        A.assemble()
        lgmaps = A.getLGMap()
        A.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        A.setLGMap(*lgmaps)
        C.destroy()
        return True


def test_a_term_can_send_the_matrix_back_to_the_forms_pattern():
    """A term whose couplings have moved on asks at begin() for a fresh matrix: the solver
    replaces A by one of the forms' nonzero pattern, the term widens it again, and Newton
    converges to the same solution as with the grown matrix (consistency of the swap)."""
    import numpy as np

    F, J, u, bcs = toy_problem()
    n_owned = u.function_space.dofmap.index_map.size_local
    fixed = bcs[0].dof_indices()[0]
    free = np.setdiff1d(np.arange(n_owned), fixed[fixed < n_owned])
    s = SNESSolver.from_config(F, J, u, bcs, SolverConfig(), prefix="renewed_")
    forms_only = s.A.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_allocated"]
    term = FarCoupling(2.0, (int(free[0]), int(free[-1])))
    term.u = u
    s.terms.append(term)
    assert s.solve().converged
    grown, first = s.A, u.x.array.copy()
    assert s.A.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_allocated"] > forms_only
    u.x.array[:] = 0.0
    term.renew = True
    result = s.solve()
    assert result.converged and s.A is not grown
    assert np.allclose(u.x.array, first, rtol=0, atol=1e-10)
    s._residual(None, s.x, s.b)
    assert s.b.norm() <= 1e-8
    s.destroy()
