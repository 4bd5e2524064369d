"""Arc-length continuation and the stability of the states along a path (core/arclength.py,
core/stability.py), against closed-form equilibrium paths, limit loads and buckling loads."""

import math
from typing import ClassVar

import numpy as np
import pytest
from petsc4py import PETSc
from scipy.optimize import minimize_scalar

from tapecoil.core.arclength import ArcLength, ArcLengthError, ArcLengthSettings
from tapecoil.core.path_system import PathSystem
from tapecoil.core.stability import StabilityAnalysis

# the von Mises truss: two bars of axial stiffness EA from the supports (+-a, 0) to the apex at
# height h0, the apex loaded through a spring of stiffness k in series (loaded point v, apex w,
# both downwards): P(w) = 2 EA (L0 - L)(h0 - w) / (L0 L), L = sqrt(a^2 + (h0 - w)^2), and
# v = w + P(w) / k. With k below -min P'(w) the loaded point snaps back.
EA, A_HALF, H0, K_SPRING = 1.0, 1.0, 0.2, 0.01


def truss_force(w):
    L0 = math.hypot(A_HALF, H0)
    L = np.hypot(A_HALF, H0 - w)
    return 2 * EA * (L0 - L) * (H0 - w) / (L0 * L)


def truss_limit():
    """The truss's limit load: the maximum of P(w), to round-off."""
    best = minimize_scalar(
        lambda w: -truss_force(w), bounds=(0.0, H0), method="bounded", options={"xatol": 1e-13}
    )
    return float(truss_force(best.x)), float(best.x)


class Truss(PathSystem):
    """The truss and its spring as a two-dof PathSystem (w, v), on one process."""

    comm = PETSc.COMM_SELF
    prefix = "test_truss_"
    options: ClassVar[dict] = {}

    def __init__(self, load_range=(-math.inf, math.inf)):
        self.state = np.zeros(2)
        self.load = 0.0
        self.load_range = load_range
        self.A = PETSc.Mat().createAIJ((2, 2), nnz=2, comm=PETSc.COMM_SELF)
        self.A.setUp()

    def vector(self):
        return PETSc.Vec().createSeq(2, comm=PETSc.COMM_SELF)

    def get_state(self, x):
        x.array[:] = self.state

    def set_state(self, x, load):
        self.state[:] = x.array_r
        self.load = load

    def residual(self, b):
        w, v = self.state
        b.array[:] = [truss_force(w) - K_SPRING * (v - w), K_SPRING * (v - w) - self.load]

    def jacobian(self):
        w, _ = self.state
        h = 1e-7
        dP = (truss_force(w + h) - truss_force(w - h)) / (2 * h)
        K = np.array([[dP + K_SPRING, -K_SPRING], [-K_SPRING, K_SPRING]])
        self.A.setValues([0, 1], [0, 1], K.ravel())
        self.A.assemble()
        return self.A


def test_truss_path_through_snap_through_and_snap_back():
    """The path of the truss under its spring, from rest to the inverted truss: every state
    on the closed-form path, the load over its maximum and back through zero to its minimum
    (a limit point in load each), the loaded point turning back twice (snap-back)."""
    truss = Truss()
    P_max, _ = truss_limit()
    path = ArcLength(truss, ArcLengthSettings(first_step=0.05 * P_max))
    states = []
    path.run(
        0.0,
        3 * P_max,
        stop=lambda p: truss.state[0] > 2.2 * H0,
        on_point=lambda p: states.append((p.load, *truss.state)),
    )
    load, w, v = np.array(states).T
    # equilibrium of the apex and of the spring: Newton's tolerance is 1e-9 of the load, here
    # never above 1.5 P_max
    tol = 2e-9 * np.abs(load).max()
    assert np.max(np.abs(load - truss_force(w))) < tol
    assert np.max(np.abs(K_SPRING * (v - w) - load)) < tol
    assert w[-1] > 2 * H0  # through to the inverted truss
    dload, dv = np.diff(load), np.diff(v)
    assert np.count_nonzero(np.diff(np.sign(dload))) == 2  # the load turns back twice
    assert np.count_nonzero(np.diff(np.sign(dv))) == 2  # and so does the loaded point
    assert load.min() < -0.9 * P_max  # the tension branch between the snaps
    iterations = [p.iterations for p in path.points[1:]]
    assert max(iterations) <= path.settings.max_iterations


def test_truss_limit_points_and_eigenvalue_through_zero():
    """The limit loads located along the path, +-P_max (the path is odd about w = h0), against
    the closed-form maximum of P(w) to 1e-6, with the eigenvalue through zero there; the states
    between them (the falling branch, load control) unstable, the others stable."""
    truss = Truss()
    P_max, _ = truss_limit()
    path = ArcLength(
        truss,
        ArcLengthSettings(first_step=0.05 * P_max),
        stability=StabilityAnalysis(1, prefix="test_truss_stab_"),
    )
    path.run(0.0, 3 * P_max, stop=lambda p: truss.state[0] > 2.2 * H0)
    kinds = [c.kind for c in path.critical]
    assert kinds == ["limit", "limit"]
    top, bottom = path.critical
    assert abs(top.load - P_max) < 1e-6 * P_max
    assert abs(bottom.load + P_max) < 1e-6 * P_max
    for c in path.critical:
        assert abs(c.eigenvalue) < 1e-6 * abs(c.initial_eigenvalue)
    # between the limit points the truss is unstable (one negative eigenvalue), outside stable
    for p in path.points:
        between = top.arc_length < p.arc_length < bottom.arc_length
        assert p.negative == (1 if between else 0)


def test_bad_input_is_refused_before_computing():
    with pytest.raises(ValueError, match="first_step"):
        ArcLengthSettings(first_step=0.0)
    with pytest.raises(ValueError, match="min_step"):
        ArcLengthSettings(first_step=1.0, min_step=-1.0)
    truss = Truss(load_range=(-1.0, 1.0))
    path = ArcLength(truss, ArcLengthSettings(first_step=0.1))
    with pytest.raises(ValueError, match="outside the problem's loads"):
        path.run(0.0, 2.0)
    with pytest.raises(ValueError, match="must point"):
        path.run(0.0, -0.5)
    with pytest.raises(ValueError, match="first_arc_length"):
        path.run(0.0, 0.5, first_arc_length=-1.0)
    assert path.points == []  # nothing computed


def test_unconverging_path_stops_with_the_last_state():
    """A step that cannot converge (one Newton iteration allowed on a nonlinear path) is
    halved down to the smallest step, then the run stops at the last converged state."""
    truss = Truss()
    P_max, _ = truss_limit()
    settings = ArcLengthSettings(
        first_step=0.5 * P_max, max_iterations=2, target_iterations=1, min_step=0.5, rtol=1e-14, atol=1e-30
    )
    path = ArcLength(truss, settings)
    with pytest.raises(ArcLengthError) as error:
        path.run(0.0, 2 * P_max)
    assert error.value.load == path.points[-1].load


def test_roof_snap_through():
    """Sze's hinged roof, h = 12.7 (verify roof-snap-through, coarse): the first limit load
    within 1 % of Sze's, the eigenvalue through zero there, the load's minimum passed too."""
    from tapecoil.verification.roof import ROOF_MESHES, roof

    result = roof(12.7, ROOF_MESHES["coarse"])
    assert result.passed, [(c.name, c.computed, c.reference) for c in result.checks]


def test_roof_snap_back():
    """Sze's hinged roof, h = 6.35 (verify roof-snap-back, coarse): the limit load within 1 %,
    and the deflection under the load turning back and forward again (snap-back)."""
    from tapecoil.verification.roof import ROOF_MESHES, roof

    result = roof(6.35, ROOF_MESHES["coarse"])
    assert result.passed, [(c.name, c.computed, c.reference) for c in result.checks]


@pytest.mark.mpi
def test_roof_two_ranks_against_one():
    """The roof's path on two ranks against the same on each rank alone: the same points and
    the same limit loads, to the Newton tolerance."""
    from mpi4py import MPI

    from tapecoil.geometry.meshes import MeshResolution
    from tapecoil.verification.roof import roof_curve

    res = MeshResolution(4, 4)
    both = roof_curve(12.7, res, MPI.COMM_WORLD, end_deflection=22.0, name="roof_mpi")
    alone = roof_curve(12.7, res, MPI.COMM_SELF, end_deflection=22.0, name="roof_self")
    assert len(both["curve"]) == len(alone["curve"])
    a, b = np.array(both["curve"], dtype=float), np.array(alone["curve"], dtype=float)
    assert np.allclose(a[:, :2], b[:, :2], rtol=1e-6, atol=1e-6 * np.abs(b[:, 0]).max())
    assert [c[0] for c in both["critical"]] == [c[0] for c in alone["critical"]] == ["limit", "limit"]
    for x, y in zip(both["critical"], alone["critical"], strict=True):
        assert abs(x[1] - y[1]) < 1e-6 * abs(y[1])


def _elastica_load(deflection_over_length: float) -> float:
    """P / P_cr of the inextensible cantilever elastica whose tip is deflected sideways by
    ``deflection_over_length`` L (Timoshenko and Gere, Theory of Elastic Stability, Sec. 2.7):
    delta / L = 2 k / K(k), P / P_cr = (2 K(k) / pi)^2, k = sin(alpha / 2)."""
    from scipy.optimize import brentq
    from scipy.special import ellipk

    k = brentq(lambda k: 2 * k / ellipk(k * k) - deflection_over_length, 1e-12, 0.999)
    return (2 * ellipk(k * k) / math.pi) ** 2


def test_euler_column_buckling_load_and_post_buckled_branch():
    """A slender cantilever column under an end force along its axis (the geometrically exact
    beam): the eigenvalue of its tangent stiffness through zero at Euler's pi^2 EI / (4 L^2),
    to 1e-3, located as a bifurcation (the load does not turn back); the branch followed from
    there along the critical mode is the elastica: the load at each tip deflection (up to 0.4
    L) within 1e-3 of the closed form. Shear and stretching shift the load by about 1e-4 at
    this slenderness (L / depth = 100), inside the tolerance."""
    from mpi4py import MPI

    from tapecoil.models.beam_problem import BeamProblem
    from tapecoil.models.beam_section import BeamSection
    from tapecoil.models.paths import beam_path
    from tapecoil.verification.beam import fixed_frame, straight_line

    L = 1.0
    section = BeamSection.rectangle(E=1.0e7, nu=0.3, width=0.02, depth=0.01)
    EI = min(section.EI2, section.EI3)
    P_cr = math.pi**2 * EI / (4 * L**2)
    problem = BeamProblem(straight_line, L, 16, section, fixed_frame, comm=MPI.COMM_WORLD, name="test_column")
    problem.clamp((0, 0, 0))
    problem.end_load((L, 0, 0), force=(-1.0, 0.0, 0.0))  # lambda = the compressive force [N]
    stability = StabilityAnalysis(3, prefix="test_column_stab_")
    path = beam_path(problem, ArcLengthSettings(first_step=0.3 * P_cr), stability=stability)
    try:
        path.run(0.0, 2 * P_cr, until_critical=True)
        (critical,) = path.critical
        assert critical.kind == "bifurcation"
        assert abs(critical.load / P_cr - 1) < 1e-3
        assert abs(critical.eigenvalue) < 1e-6 * abs(critical.initial_eigenvalue)
        assert [p.stable for p in path.points[:-1]] == [True] * (len(path.points) - 1)
        # the post-buckled branch, leaving along the mode
        branch = beam_path(problem, ArcLengthSettings(first_step=0.01 * P_cr, max_step=50.0), stability=None)
        tips = []

        def record(point):
            u = problem.position((L, 0, 0)) - np.array([L, 0, 0])
            tips.append((point.load, math.hypot(u[1], u[2])))

        try:
            branch.run(
                critical.load,
                2 * P_cr,
                along=(critical.mode, 0.0),
                first_arc_length=0.01 * L,
                stop=lambda _p: tips[-1][1] > 0.4 * L,
                on_point=record,
            )
        finally:
            branch.destroy()
    finally:
        path.destroy()
    checked = [(P, d) for P, d in tips if d > 0.02 * L]
    assert len(checked) >= 5
    for P, d in checked:
        assert abs(P / P_cr / _elastica_load(d / L) - 1) < 1e-3, (P / P_cr, d)


def test_solver_stability_of_a_pinched_roof():
    """solver_stability on a plain load-stepped solve: the roof loaded to 90 % of its limit
    load is stable, its eigenvalue nearest zero closer to zero than at rest (the stiffness
    falls towards the limit point); a solve is judged without any continuation."""
    from tapecoil.core.newton import SNESSolver
    from tapecoil.core.stability import solver_stability
    from tapecoil.geometry.meshes import MeshResolution
    from tapecoil.verification.roof import SZE_PMAX, SZE_ROOF_LIMIT, roof_problem

    problem = roof_problem(12.7, MeshResolution(4, 4), name="test_roof_stab")
    F, J = problem.forms()
    solver = SNESSolver(F, J, problem.model.q, problem.bcs, prefix="test_roof_stab_")
    solver.point_forces.extend(problem.point_forces)
    try:
        at_rest = solver_stability(solver)
        problem.set_load(0.9 * SZE_ROOF_LIMIT[12.7][0] * SZE_PMAX)
        assert solver.solve().converged
        loaded = solver_stability(solver)
    finally:
        solver.destroy()
    assert at_rest.stable and loaded.stable
    assert 0 < loaded.eigenvalues[0] < 0.5 * at_rest.eigenvalues[0]
