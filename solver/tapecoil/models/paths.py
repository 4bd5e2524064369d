"""Equilibrium paths of the project's problems by arc-length continuation
(:mod:`tapecoil.core.arclength`): a :class:`~tapecoil.models.problem.ShellProblem` or a
:class:`~tapecoil.models.beam_problem.BeamProblem` with its own supports, loads and solver
settings, its load parameter an unknown.

    path = shell_path(problem, ArcLengthSettings(first_step=100.0), stability=StabilityAnalysis())
    try:
        path.run(0.0, 3000.0, stop=lambda point: deflection() > 30.0)
    finally:
        path.destroy()
"""

from __future__ import annotations

import math

from tapecoil.config import SolverConfig
from tapecoil.core.arclength import ArcLength, ArcLengthSettings
from tapecoil.core.newton import SNESSolver
from tapecoil.core.path_system import SolverSystem


class _OwnedSolverSystem(SolverSystem):
    """A :class:`SolverSystem` whose solver is made for the path and destroyed with it."""

    def destroy(self) -> None:
        self.solver.destroy()


def shell_path(
    problem,
    settings: ArcLengthSettings,
    *,
    stability=None,
    solver_config: SolverConfig | None = None,
    prefix: str | None = None,
    options: dict | None = None,
    load_range=(-math.inf, math.inf),
) -> ArcLength:
    """An arc-length path of ``problem`` (a ShellProblem), its solver made as
    :meth:`ShellProblem.solve` makes it (``solver_config``'s tolerances are not used: the path's
    are ``settings``'); ``stability``: a :class:`~tapecoil.core.stability.StabilityAnalysis` for
    every converged state; ``load_range``: the loads the problem is defined for."""
    solver = problem.snes_solver(solver_config or SolverConfig(), prefix, options)
    system = _OwnedSolverSystem(solver, problem.set_load, load_range=load_range)
    return ArcLength(system, settings, stability=stability)


def beam_path(
    problem,
    settings: ArcLengthSettings,
    *,
    stability=None,
    options: dict | None = None,
    load_range=(-math.inf, math.inf),
) -> ArcLength:
    """An arc-length path of ``problem`` (a BeamProblem) from its committed state; every
    accepted step is committed as :meth:`BeamProblem.solve` commits one (the beam's rotations
    are increments from its last accepted state)."""
    residual, jacobian = problem.forms()
    solver = SNESSolver(
        residual,
        jacobian,
        problem.model.q,
        problem.bcs,
        prefix=f"{problem.name}_",
        options={"pc_factor_mat_solver_type": "mumps", "pc_type": "cholesky", **(options or {})},
        state_scale=problem.model.rounding_scale(),
    )
    solver.point_forces = problem.point_forces
    system = _OwnedSolverSystem(
        solver, problem.set_load, commit=lambda _load: problem.commit(), load_range=load_range
    )
    return ArcLength(system, settings, stability=stability)
