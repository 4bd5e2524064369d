"""A thin PETSc SNES wrapper over DOLFINx assembly, the same on DOLFINx 0.9 to 0.11.

Newton with a line search and a direct solver (MUMPS) by default. Each solver has an options
prefix named by its caller (``coil_``, ``deploy_``, ``verify_rollup_``), as DOLFINx's
NonlinearProblem has, so that any PETSc option can be set for it on the command line of the
``tapecoil`` command or of a user's script (``-coil_snes_monitor``; see
:mod:`~tapecoil.core.petsc_options`). The wrapper owns its vectors and matrix and assembles the residual
with Dirichlet conditions applied by lifting, so that a Newton iterate that does not yet satisfy
the (changed) boundary values is driven onto them: the residual on a constrained dof is x - g.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import dolfinx
import dolfinx.fem.petsc
import numpy as np
from petsc4py import PETSc

from tapecoil.core import compat, jit
from tapecoil.core.convergence import ResidualTest
from tapecoil.core.petsc_options import DEFAULT_PETSC_OPTIONS, check_prefix, options_in_database


@dataclass
class SolveResult:
    """Outcome of one nonlinear solve."""

    converged: bool
    iterations: int
    reason: int
    residual_norm: float

    @property
    def reason_name(self) -> str:
        names = {v: k for k, v in vars(PETSc.SNES.ConvergedReason).items() if isinstance(v, int)}
        return names.get(self.reason, str(self.reason))


class PerUnitLoad:
    """A point force's magnitude: ``factor`` times the load parameter ``load`` (anything with a
    ``value``, a DOLFINx Constant), read when the residual is."""

    def __init__(self, load, factor: float):
        self.load, self.factor = load, factor

    @property
    def value(self) -> float:
        return self.factor * float(self.load.value)


@dataclass
class PointForce:
    """A concentrated force on the dofs ``dofs`` (owned, local indices) of magnitude ``magnitude``.

    ``magnitude`` is an object with a ``value`` (a dolfinx Constant works) so that load
    stepping can change it.
    """

    dofs: np.ndarray
    magnitude: object


def assemble_residual(b, F_form, J_form, bcs, q, terms=(), point_forces=(), extra=None) -> None:
    """The residual F(q) into b: Dirichlet conditions by lifting (the residual on a constrained
    dof is q - g), then the assembled terms' parts, the point forces (residual = internal -
    external) and ``extra(owned local array)``, before the constrained rows are set."""
    with b.localForm() as b_local:
        b_local.set(0.0)
    dolfinx.fem.petsc.assemble_vector(b, F_form)
    dolfinx.fem.petsc.apply_lifting(b, [J_form], bcs=[bcs], x0=[q.x.petsc_vec], alpha=-1.0)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    for term in terms:
        term.add_residual(b)
    with b.localForm() as b_local:
        for force in point_forces:
            b_local.array[force.dofs] -= force.magnitude.value
        if extra is not None:
            extra(b_local.array)
    dolfinx.fem.petsc.set_bc(b, bcs, q.x.petsc_vec, -1.0)


def assemble_jacobian(A, J_form, bcs, terms=()) -> list:
    """The Jacobian's forms into A (zeroed first; Dirichlet rows and columns set) and the
    terms' parts; A is left for its caller to assemble. Returns the terms' answers to whether
    they widened A's pattern."""
    A.zeroEntries()
    compat.assemble_matrix(A, J_form, bcs)
    return [term.add_jacobian(A) for term in terms]


def run_snes(snes, x, prefix: str, options: dict, timings: dict) -> SolveResult:
    """``snes.solve`` from x with ``options`` under ``prefix`` in PETSc's database for the
    solve; adds the wall time and iterations to ``timings``. Converged means a positive reason
    and a finite residual."""
    t0 = time.perf_counter()
    with options_in_database(prefix, options):
        snes.solve(None, x)
    timings["solve"] += time.perf_counter() - t0
    timings["iterations"] += snes.getIterationNumber()
    reason = snes.getConvergedReason()
    norm = snes.getFunctionNorm()
    return SolveResult(reason > 0 and bool(np.isfinite(norm)), snes.getIterationNumber(), reason, float(norm))


def create_snes(comm, prefix, options, function, jacobian, tolerances, convergence, monitor=None):
    """A SNES under ``prefix``: ``function`` = (callback, residual vector), ``jacobian`` =
    (callback, matrix), ``tolerances`` = (rtol, atol, max_it), the residual test ``convergence``
    installed before ``options`` (PETSc names without the prefix, over which the command line
    wins) are read. A non-finite residual ends a solve as diverged instead of raising."""
    snes = PETSc.SNES().create(comm)
    snes.setOptionsPrefix(prefix)
    snes.setFunction(*function)
    snes.setJacobian(*jacobian)
    rtol, atol, max_it = tolerances
    snes.setTolerances(rtol=rtol, atol=atol, max_it=max_it)
    convergence.install(snes)  # before the options are read: they may change it
    if monitor is not None:
        snes.setMonitor(monitor)
    with options_in_database(prefix, options):
        snes.setFromOptions()
        snes.getKSP().setFromOptions()
    snes.setErrorIfNotConverged(False)
    return snes


class SNESSolver:
    """Newton (PETSc SNES) for F(q) = 0 with Jacobian J and Dirichlet conditions ``bcs``.

    ``prefix``: the PETSc options prefix, named by the caller (letters, digits and underscores,
    ending in an underscore). ``options`` override :data:`DEFAULT_PETSC_OPTIONS` (PETSc option
    names without prefix); ``rtol``, ``atol`` and ``max_it`` set the SNES tolerances;
    ``state_scale``: a Function of q's space, the magnitude of what q is added to (see
    :class:`~tapecoil.core.convergence.ResidualTest`). Whatever
    the PETSc options database holds under the prefix (the command line) wins over all of these.
    """

    def __init__(
        self, F, J, q, bcs, *, prefix, options=None, rtol=1e-8, atol=1e-10, max_it=25, state_scale=None
    ):
        check_prefix(prefix)
        self.q = q
        self.bcs = list(bcs)
        self.F_form = jit.form(F)
        self.J_form = jit.form(J)
        V = q.function_space
        self.b = compat.create_vector(V)
        self.x = compat.create_vector(V)
        self.A = dolfinx.fem.petsc.create_matrix(self.J_form)
        self.norms: list[float] = []
        self.point_forces: list[PointForce] = []
        # assembled terms beyond the forms (contact between distant parts of the mesh): objects
        # with add_residual(b) and add_jacobian(A), called with the state in place, after the
        # forms and before the Dirichlet rows are set; add_jacobian returns True when it has
        # widened A's nonzero pattern; begin() is called before every solve and returns True
        # when A should start again from the forms' pattern (the term's couplings have moved
        # on: a pattern that only grows makes every factorisation dearer). A term with
        # apply_coupling(x, y) (y += K x) applies that part K of its Jacobian instead of
        # assembling it: Newton's operator is then A + K (:class:`JacobianOperator`), which
        # the factorised A preconditions in a Krylov solve
        self.terms: list = []
        self._operator = None
        # cumulative wall times [s]: residual and Jacobian assembly, and whole solves
        self.timings = {"residual": 0.0, "jacobian": 0.0, "solve": 0.0, "iterations": 0}

        self.prefix = prefix
        self.options = {**DEFAULT_PETSC_OPTIONS, **(options or {})}
        self.convergence = ResidualTest(
            None if state_scale is None else state_scale.x.array[: self.x.getLocalSize()]
        )
        self.snes = create_snes(
            V.mesh.comm,
            prefix,
            self.options,
            (self._residual, self.b),
            (self._jacobian, self.A),
            (rtol, atol, max_it),
            self.convergence,
            monitor=lambda _snes, _it, norm: self.norms.append(norm),
        )

    def _update_state(self, x) -> None:
        qv = self.q.x.petsc_vec
        if x.handle != qv.handle:
            x.copy(qv)
        qv.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def _residual(self, _snes, x, b) -> None:
        t0 = time.perf_counter()
        self._update_state(x)
        assemble_residual(b, self.F_form, self.J_form, self.bcs, self.q, self.terms, self.point_forces)
        self.timings["residual"] += time.perf_counter() - t0

    def _jacobian(self, _snes, x, J, P) -> None:
        # J is P but for an operator P preconditions (a term's applied part, -snes_mf_operator)
        t0 = time.perf_counter()
        self._update_state(x)
        A = P
        widened = assemble_jacobian(A, self.J_form, self.bcs, self.terms)
        A.assemble()
        if J.handle != P.handle:
            J.assemble()
        self.convergence.update_floor(A, x)
        if any(widened):
            # a widened pattern replaces A's storage (PETSc's header merge), which the
            # factorisation does not notice: make it analyse the new pattern afresh
            self.snes.getKSP().getPC().reset()
        self.timings["jacobian"] += time.perf_counter() - t0

    def _renew_matrix(self) -> None:
        """Replace A by a matrix of the forms' nonzero pattern alone (collective); the terms
        widen it again with the couplings they have now."""
        old = self.A
        self.A = dolfinx.fem.petsc.create_matrix(self.J_form)
        self.snes.setJacobian(self._jacobian, self.A if self._operator is None else self._operator, self.A)
        self.snes.getKSP().getPC().reset()
        old.destroy()

    def _use_operator(self) -> None:
        if self._operator is None and any(hasattr(term, "apply_coupling") for term in self.terms):
            operator = JacobianOperator(lambda: self.A, lambda: self.terms)
            J = PETSc.Mat().createPython(self.A.getSizes(), operator, comm=self.A.getComm())
            J.setUp()
            self.snes.setJacobian(self._jacobian, J, self.A)
            self._operator = J

    def compute_residual(self, b) -> None:
        """The residual at the state ``q`` as it is into b (a driver of its own, arc-length
        continuation, iterating outside the SNES)."""
        self._residual(None, self.q.x.petsc_vec, b)

    def compute_jacobian(self):
        """The Jacobian at the state ``q`` as it is, assembled into this solver's matrix A."""
        self._jacobian(None, self.q.x.petsc_vec, self.A, self.A)
        return self.A

    def solve(self) -> SolveResult:
        """Solve from the current state ``q``; on failure ``q`` holds the last iterate."""
        self._use_operator()
        self.norms.clear()
        if any([term.begin() for term in self.terms]):  # a list: every term's begin() runs
            self._renew_matrix()
        self.q.x.petsc_vec.copy(self.x)
        result = run_snes(self.snes, self.x, self.prefix, self.options, self.timings)
        if result.converged:
            self._update_state(self.x)
        return result

    def timing_per_iteration(self) -> dict[str, float]:
        """Mean wall time per Newton iteration [s]: assembly (residual + Jacobian), the rest, and
        the terms' own share of both.

        The rest is the linear solve (factorisation and substitution) plus SNES overhead. The
        terms' share (``terms``) is what the terms that count their time (a ``seconds()``
        method) spent, in the assembly and in the operator's applied part: a part of the two.
        """
        its = max(self.timings["iterations"], 1)
        assembly = self.timings["residual"] + self.timings["jacobian"]
        terms = sum(term.seconds() for term in self.terms if hasattr(term, "seconds"))
        return {
            "assembly": assembly / its,
            "linear_solve": (self.timings["solve"] - assembly) / its,
            "terms": terms / its,
        }

    @classmethod
    def from_config(
        cls,
        F,
        J,
        q,
        bcs,
        solver_config,
        *,
        prefix,
        defaults=None,
        options=None,
        state_scale=None,
        **overrides,
    ):
        """A solver with the tolerances and PETSc options of a :class:`SolverConfig`.

        ``prefix``: the PETSc options prefix (see the class). PETSc options, each level over the
        one before: :data:`DEFAULT_PETSC_OPTIONS`, ``defaults`` (the caller's), the
        configuration's ``[solver] petsc_options``, ``options`` (the phase's own table, e.g.
        ``[coiling] petsc_options``), ``overrides`` (what the caller cannot do without); the
        command line over all of them.
        """
        merged = {**(defaults or {}), **solver_config.petsc_options, **(options or {}), **overrides}
        return cls(
            F,
            J,
            q,
            bcs,
            prefix=prefix,
            options=merged,
            rtol=solver_config.rtol,
            atol=solver_config.atol,
            max_it=solver_config.max_newton,
            state_scale=state_scale,
        )

    def destroy(self) -> None:
        for obj in (self.snes, self.A, self.b, self.x, self._operator):
            if obj is not None:
                obj.destroy()


class JacobianOperator:
    """Newton's operator A + sum of the terms' applied parts, as a PETSc python matrix's context:
    ``matrix()`` the assembled matrix A (a solver's, which it may replace), ``terms()`` the
    solver's terms."""

    def __init__(self, matrix, terms):
        self.matrix, self.terms = matrix, terms

    def _applied(self) -> list:
        return [term for term in self.terms() if hasattr(term, "apply_coupling")]

    def mult(self, _mat, x, y) -> None:
        self.matrix().mult(x, y)
        for term in self._applied():
            term.apply_coupling(x, y)

    def multTranspose(self, _mat, x, y) -> None:
        """(A + K)^T x: for a trust region's steepest descent (``snes_type newtontr``)."""
        self.matrix().multTranspose(x, y)
        for term in self._applied():
            term.apply_coupling(x, y, transpose=True)
