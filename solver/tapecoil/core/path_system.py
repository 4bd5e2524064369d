"""What a path-following method needs of a discrete problem R(x, lambda) = 0
(:class:`PathSystem`), and the project's Newton solver behind that interface
(:class:`SolverSystem`: its assembly, its supports, its PETSc options prefix). The arc-length
continuation (:mod:`tapecoil.core.arclength`) and the stability of its states
(:mod:`tapecoil.core.stability`) work on any :class:`PathSystem`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import ClassVar

import numpy as np
from petsc4py import PETSc

__all__ = ["PathSystem", "SolverSystem"]


class PathSystem:
    """What arc-length continuation needs of a discrete problem R(x, lambda) = 0.

    ``comm``; ``prefix`` (PETSc options of its linear solver); ``options`` (PETSc options under
    it, without the prefix); ``load_range`` (the loads the problem is defined for).
    """

    comm = None
    prefix = "path_"
    options: ClassVar[dict] = {}
    load_range = (-math.inf, math.inf)

    def vector(self):
        """A new vector of the state's layout."""
        raise NotImplementedError

    def get_state(self, x) -> None:
        """Copy the state in place into x."""
        raise NotImplementedError

    def set_state(self, x, load: float) -> None:
        """Put the state x and the load parameter in place."""
        raise NotImplementedError

    def residual(self, b) -> None:
        """R at the state and load in place into b (held dofs: state minus held value)."""
        raise NotImplementedError

    def jacobian(self):
        """dR/dx at the state in place, assembled (held dofs: identity rows and columns)."""
        raise NotImplementedError

    def held_rows(self) -> np.ndarray:
        """Global indices of the owned held (Dirichlet) dofs."""
        return np.zeros(0, dtype=PETSc.IntType)

    def commit(self, load: float) -> None:
        """After an accepted step: a model with state outside x (a beam's frames) moves it on."""


class SolverSystem(PathSystem):
    """The project's :class:`~tapecoil.core.newton.SNESSolver` as a :class:`PathSystem`:
    ``set_load(value)`` puts the load parameter (and whatever it drives: turned edges) in
    place; ``commit(load)`` runs after each accepted step; ``load_range``: the loads the problem
    is defined for."""

    def __init__(
        self, solver, set_load: Callable[[float], None], commit=None, load_range=(-math.inf, math.inf)
    ):
        self.solver = solver
        self._set_load = set_load
        self._commit = commit
        self.comm = solver.q.function_space.mesh.comm
        self.prefix = solver.prefix
        self.options = solver.options
        self.load_range = tuple(load_range)

    def vector(self):
        return self.solver.x.duplicate()

    def get_state(self, x) -> None:
        self.solver.q.x.petsc_vec.copy(x)

    def set_state(self, x, load: float) -> None:
        qv = self.solver.q.x.petsc_vec
        x.copy(qv)
        qv.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        self._set_load(load)

    def residual(self, b) -> None:
        self.solver.compute_residual(b)

    def jacobian(self):
        return self.solver.compute_jacobian()

    def held_rows(self) -> np.ndarray:
        from tapecoil.core.stability import held_rows

        return held_rows(self.solver)

    def commit(self, load: float) -> None:
        if self._commit is not None:
            self._commit(load)
