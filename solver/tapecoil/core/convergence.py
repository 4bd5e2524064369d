"""The SNES convergence test of :class:`tapecoil.core.newton.SNESSolver`: the residual alone.

PETSc's default test also ends a solve on a small Newton step (``snes_stol``) relative to the
state's norm; with director angles of tens of radians in the state, a small step says nothing
about the residual. This test ends a solve on the residual: below atol, below rtol times its
first value, or at its round-off floor, estimated from the last Jacobian.
"""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc

# The residual's round-off floor over the part of it that the state's rounding explains: the
# evaluation of the residual rounds too, in sums of terms each about as large as J x, and a
# residual that carries other data (a time step's previous velocity and acceleration) rounds
# those. The stagnation levels seen lie below this margin: under |J d| in the shell's coiling
# and relaxation solves, a few |J d| in generalized-alpha oscillators, whose state has decayed
# below the previous step's data
ROUND_OFF_MARGIN = 10.0


class ResidualTest:
    """A SNES convergence test (``snes.setConvergenceTest(test)``) with the floor it estimates.

    ``floor``: the residual's round-off floor at the last Jacobian (0 before the first of a
    solve); ``floor_ends``: how many solves ended at it. ``state_scale``: the magnitude of what
    each component of the state is added to (a shell's displacement to the reference position
    phi0, see :meth:`NaghdiShell.rounding_scale`), owned values; None for none.
    """

    def __init__(self, state_scale: np.ndarray | None = None):
        self.state_scale = 0.0 if state_scale is None else np.abs(np.asarray(state_scale))
        self.floor = 0.0
        self.floor_ends = 0
        self._first_norm = 0.0
        self._rounding = None

    def install(self, snes) -> None:
        """Make this the convergence test of ``snes``; call it before the options are read.

        PETSc's step-length test goes (``snes_stol`` 0: against director angles of tens of
        radians a small Newton step says nothing about the residual); its divergence test
        (``snes_divergence_tolerance``, 1e4 times the first residual) stays, as PETSc has it.
        ``-<prefix>snes_convergence_test default`` on the command line brings PETSc's own test
        back in place of this one.
        """
        rtol, atol, _stol, max_it = snes.getTolerances()
        snes.setTolerances(rtol=rtol, atol=atol, stol=0.0, max_it=max_it)
        snes.setConvergenceTest(self)

    def update_floor(self, A, x) -> None:
        """The residual's round-off floor at x: :data:`ROUND_OFF_MARGIN` times the norm of J d,
        d the rounding of x's last bit.

        A state stored in double precision is known to eps |x_i| in each component, and what it
        is added to (the reference position of a displacement, s_i) to eps |s_i|, so no Newton
        iterate can bring the residual below the change such a rounding makes to it: J d with
        d_i = ±eps (|x_i| + |s_i|). The signs are fixed pseudo-random ones of the global dof
        index (a sum with one sign would cancel in a rigid motion), the same on any number of
        ranks. One matrix-vector product per Jacobian.
        """
        if self._rounding is None:
            lo, hi = x.getOwnershipRange()
            index = np.arange(lo, hi, dtype=np.uint64)
            # Knuth's multiplicative hash: a sign per global index, uncorrelated with the layout
            self._signs = np.where((index * np.uint64(2654435761) >> np.uint64(15)) & np.uint64(1), 1.0, -1.0)
            self._rounding = x.duplicate()
            self._image = x.duplicate()
        self._rounding.array[:] = self._signs * (np.abs(x.array_r) + self.state_scale) * np.finfo(float).eps
        A.mult(self._rounding, self._image)
        self.floor = ROUND_OFF_MARGIN * self._image.norm()

    def __call__(self, snes, it, norms):
        """SNES convergence test on the residual alone.

        Converged when the residual norm is below atol, below rtol times its first value, or at
        its round-off floor (:meth:`update_floor`, from the previous Newton iteration's
        Jacobian): a solve that starts at the floor (a pseudo-transient relaxation's, late in
        its pseudo-time) cannot go further down and ends there, while a small step with a
        residual above the floor does not end a solve. Divergence as PETSc judges it: the
        residual grown beyond ``snes_divergence_tolerance`` times its first value, or max_it.
        """
        _xnorm, _step, fnorm = norms
        rtol, atol, _stol, max_it = snes.getTolerances()
        if not np.isfinite(fnorm):
            return PETSc.SNES.ConvergedReason.DIVERGED_FNORM_NAN
        if it == 0:
            self._first_norm = fnorm
            self.floor = 0.0
        if fnorm <= atol:
            return PETSc.SNES.ConvergedReason.CONVERGED_FNORM_ABS
        if it > 0 and fnorm <= rtol * self._first_norm:
            return PETSc.SNES.ConvergedReason.CONVERGED_FNORM_RELATIVE
        if it > 0 and fnorm <= self.floor:
            self.floor_ends += 1
            return PETSc.SNES.ConvergedReason.CONVERGED_FNORM_ABS
        divergence = snes.getDivergenceTolerance()  # < 0: none (PETSc.UNLIMITED)
        if it > 0 and divergence > 0 and fnorm > divergence * self._first_norm:
            return PETSc.SNES.ConvergedReason.DIVERGED_DTOL
        if it >= max_it:
            return PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
        return PETSc.SNES.ConvergedReason.ITERATING
