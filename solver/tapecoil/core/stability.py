"""The stability of an equilibrium state: the tangent stiffness's eigenvalues nearest zero, with
the supports applied, and how many of its eigenvalues are negative.

A state is stable when its tangent stiffness (the Hessian of the energy, under conservative
loads) is positive definite on the dofs the supports leave free. The held dofs' rows and columns
of a Jacobian assembled with Dirichlet conditions are identity ones; here they are given a
diagonal far above the rest of the spectrum, so that they take no part in what is sought.

One LDL^T factorisation of that matrix (MUMPS, symmetric) gives both: its inertia is the exact
count of negative eigenvalues (Sylvester's law), and SLEPc's shift-and-invert about zero on the
same factors gives the eigenvalues nearest zero, and their modes. An eigenvalue passing through
zero along a path marks a limit point or a bifurcation (:mod:`tapecoil.core.arclength`).

The eigenvalues are those of the stiffness matrix itself, in the units of its rows and columns
(force over displacement, moment over rotation): their sign is what judges a state, their size
compares states of one discretisation only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from tapecoil.core.petsc_options import check_prefix, options_in_database

# the held dofs' diagonal over the largest diagonal entry: far above every sought eigenvalue
HELD_DIAGONAL = 1e3

STABILITY_OPTIONS = {
    "st_type": "sinvert",
    "st_ksp_type": "preonly",
    "st_pc_type": "cholesky",
    "st_pc_factor_mat_solver_type": "mumps",
    # MUMPS reports the inertia of a parallel factorisation only without ScaLAPACK at the root
    "st_mat_mumps_icntl_13": 1,
    # a singular pivot (a state exactly at a critical point) is perturbed, not an error
    "st_mat_mumps_icntl_24": 1,
}


@dataclass
class StabilityResult:
    """The eigenvalues nearest zero (ascending), the count of negative eigenvalues, and the
    mode of the eigenvalue nearest zero (a PETSc vector, when asked for)."""

    eigenvalues: list[float]
    negative: int
    mode: object = None

    @property
    def stable(self) -> bool:
        return self.negative == 0


class StabilityAnalysis:
    """``count`` eigenvalues nearest zero of a tangent stiffness with its supports applied.

    ``prefix``: the PETSc options prefix of the SLEPc solver (``-<prefix>eps_monitor``);
    ``options``: options under it (without the prefix) over :data:`STABILITY_OPTIONS`.
    """

    def __init__(self, count: int = 3, *, prefix: str = "stability_", options: dict | None = None):
        if count < 1:
            raise ValueError(f"stability: count {count} must be positive")
        check_prefix(prefix)
        self.count = count
        self.prefix = prefix
        self.options = {**STABILITY_OPTIONS, **(options or {})}

    def analyse(self, A, held_rows: np.ndarray, vectors: bool = False) -> StabilityResult:
        """The stability of the state whose assembled Jacobian is A; ``held_rows``: the global
        indices of the owned held dofs (collective)."""
        from slepc4py import SLEPc

        B = A.duplicate(copy=True)
        try:
            diagonal = B.getDiagonal()
            big = HELD_DIAGONAL * max(diagonal.norm(PETSc.NormType.NORM_INFINITY), 1e-300)
            diagonal.destroy()
            B.zeroRowsColumns(np.asarray(held_rows, dtype=PETSc.IntType), diag=big)
            B.setOption(PETSc.Mat.Option.SYMMETRIC, True)
            eps = SLEPc.EPS().create(B.getComm())
            try:
                eps.setOptionsPrefix(self.prefix)
                eps.setOperators(B)
                eps.setProblemType(SLEPc.EPS.ProblemType.HEP)
                size = B.getSize()[0]
                # a small system (an algebraic test problem) bounds the search space
                eps.setDimensions(min(self.count, size), min(size, max(2 * self.count, self.count + 15)))
                eps.setTarget(0.0)
                eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
                with options_in_database(self.prefix, self.options):
                    eps.setFromOptions()
                    eps.solve()
                    factor = eps.getST().getKSP().getPC().getFactorMatrix()
                    negative, _zero, _positive = factor.getInertia()
                found = eps.getConverged()
                if found < 1:
                    raise RuntimeError("stability: SLEPc found no eigenvalue near zero")
                values = [eps.getEigenvalue(i).real for i in range(min(found, self.count))]
                mode = None
                if vectors:
                    nearest = int(np.argmin(np.abs(values)))
                    mode = B.createVecRight()
                    eps.getEigenvector(nearest, mode)
                return StabilityResult(sorted(values), int(negative), mode)
            finally:
                eps.destroy()
        finally:
            B.destroy()


def solver_stability(solver, count: int = 3, *, prefix: str | None = None) -> StabilityResult:
    """The stability of the state a :class:`~tapecoil.core.newton.SNESSolver` holds (its ``q``):
    the eigenvalues nearest zero of its Jacobian there with its Dirichlet conditions applied,
    and the count of negative ones (collective). Usable after any converged solve."""
    A = solver.compute_jacobian()
    analysis = StabilityAnalysis(count, prefix=prefix or f"{solver.prefix}stability_")
    return analysis.analyse(A, held_rows(solver))


def held_rows(solver) -> np.ndarray:
    """Global indices of the owned dofs an SNESSolver's Dirichlet conditions hold."""
    from tapecoil.core.dofs import owned_constrained_dofs

    lo, _ = solver.x.getOwnershipRange()
    held = owned_constrained_dofs(solver.q.function_space, solver.bcs)
    return np.unique(held).astype(PETSc.IntType) + lo
