"""Newton (PETSc SNES) over two DOLFINx problems on two meshes, joined through a few dofs.

Two problems, each a residual form, its Jacobian, a state and Dirichlet conditions
(:class:`Block`), are solved as one: the unknowns of both in one vector, one Jacobian factorised
by MUMPS. They are joined by an energy E(q0, c) stated on the first problem's mesh, whose
parameters c are a few dofs of the second problem's state (:class:`DofCoupling`: a shell's edge
tied to a beam's end node, whose six dofs are c). E's derivatives in q0 join the first block's
forms; its derivatives in c, an n-vector, n vectors on the first space and an n x n matrix
(UFL differentiates E with respect to c as a variable), are placed in the second block's rows
and in the off-diagonal blocks. The joint matrix is one AIJ matrix: its pattern is that of a
PETSc MATNEST of the four blocks converted to AIJ, made once; at every Newton iteration each
block's form is assembled straight into its diagonal block (a local reference, as DOLFINx's
block assembly does, so that no form couples the two meshes) and the coupling's entries are
added by their global rows and columns. Converting the MATNEST at every iteration instead took
a quarter of the Jacobian's time on two ranks.

The flat numbering is PETSc's for a MATNEST: each rank's rows of the first block, then its rows
of the second.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil.core import compat, jit
from tapecoil.core.convergence import ResidualTest
from tapecoil.core.dofs import global_size, owned_constrained_dofs, owned_size
from tapecoil.core.newton import JacobianOperator, SolveResult, assemble_residual, create_snes, run_snes
from tapecoil.core.numbering import Numbering, block_row_starts, joint_numbering
from tapecoil.core.petsc_options import DEFAULT_PETSC_OPTIONS, check_prefix

__all__ = ["Block", "CoupledSNESSolver", "CouplingGroup", "DofCoupling", "JointState"]


@dataclass
class Block:
    """One problem of a coupled solve: residual F and Jacobian J (UFL forms) of the state q,
    Dirichlet conditions, point forces (:class:`~tapecoil.core.newton.PointForce`) and the state
    scale of the round-off floor (a Function of q's space, or None)."""

    F: object
    J: object
    q: dolfinx.fem.Function
    bcs: list = field(default_factory=list)
    point_forces: list = field(default_factory=list)
    state_scale: dolfinx.fem.Function | None = None


class DofCoupling:
    """An energy E(q0, c) on the first block's mesh whose parameters c (n values) are dofs of the
    second block's state q1.

    ``dofs``: for each component of c, its index in q1's local dof array on the rank that owns it
    and -1 elsewhere (each component owned by exactly one rank). Build E with :attr:`variable`
    for c, then :meth:`set_energy`. Collective.
    """

    def __init__(self, mesh0, q1: dolfinx.fem.Function, dofs):
        dofs = np.asarray(dofs, dtype=np.int64)
        V1 = q1.function_space
        comm = V1.mesh.comm
        owned = dofs >= 0
        if np.any(dofs[owned] >= owned_size(V1)):
            raise ValueError("coupling: a dof given as owned is a ghost on this rank")
        counts = comm.allreduce(owned.astype(int), op=MPI.SUM)
        if np.any(counts != 1):
            raise ValueError(
                f"coupling: each coupled dof must be owned by one rank, counts {counts.tolist()}"
            )
        bs = V1.dofmap.index_map_bs
        mine = np.zeros(len(dofs), dtype=np.int64)
        if owned.any():  # a rank may hold none of the second block's dofs
            blocks = V1.dofmap.index_map.local_to_global((dofs[owned] // bs).astype(np.int32))
            mine[owned] = blocks * bs + dofs[owned] % bs
        self.q1 = q1
        self.dofs = dofs
        self.owned = owned
        self.global_dofs = comm.allreduce(mine, op=MPI.SUM).astype(PETSc.IntType)
        self.c = dolfinx.fem.Constant(mesh0, np.zeros(len(dofs)))
        self.variable = ufl.variable(self.c)
        self.comm = comm
        self.cells = np.zeros(0, dtype=np.int32)

    def set_energy(self, density, measure, q0: dolfinx.fem.Function, cells) -> None:
        """E = integral of ``density`` (UFL, in q0 and :attr:`variable`) with ``measure``, whose
        integration entities lie in the (local) ``cells`` of q0's mesh.

        E's derivatives in c are gathered by three forms, not one per entry: the gradient and the
        Hessian tested with piecewise constant vectors and matrices, whose cell values summed over
        the mesh are the entries, and the mixed derivatives as one matrix of those vectors'
        rows against q0's space, summed over the cells by a product with its transpose. A tied
        window is rebuilt at every move, and creating a form per entry, each hashed and looked
        up in the JIT cache, dominated the rebuild."""
        n = len(self.dofs)
        self.cells = np.asarray(cells, dtype=np.int32)
        V0 = q0.function_space
        mesh = V0.mesh
        energy = density * measure
        self.residual0 = ufl.derivative(energy, q0, ufl.TestFunction(V0))
        self.jacobian0 = ufl.derivative(self.residual0, q0, ufl.TrialFunction(V0))
        gradient = ufl.diff(density, self.variable)
        hessian = ufl.diff(gradient, self.variable)
        vectors = dolfinx.fem.functionspace(mesh, ("DG", 0, (n,)))
        matrices = dolfinx.fem.functionspace(mesh, ("DG", 0, (n, n)))
        tested = ufl.inner(gradient, ufl.TestFunction(vectors)) * measure
        # (form, the vector its cell values are assembled into)
        self._gradient = (jit.form(tested), compat.create_vector(vectors))
        self._hessian = (
            jit.form(ufl.inner(hessian, ufl.TestFunction(matrices)) * measure),
            compat.create_vector(matrices),
        )
        self._mixed = jit.form(ufl.derivative(tested, q0, ufl.TrialFunction(V0)))
        self._mixed_matrix = dolfinx.fem.petsc.create_matrix(self._mixed)
        # e_j: ones at component j of every cell, so that M^T e_j sums the cells' rows of j
        self._components = []
        for j in range(n):
            e = self._mixed_matrix.createVecLeft()
            e.array[:] = 0.0
            e.array[j::n] = 1.0
            self._components.append(e)
        self.energy = jit.form(energy)

    def read(self) -> None:
        """c from q1's current values (collective)."""
        values = np.zeros(len(self.dofs))
        values[self.owned] = self.q1.x.array[self.dofs[self.owned]]
        self.c.value[:] = self.comm.allreduce(values, op=MPI.SUM)

    def _scalar(self, form) -> float:
        return self.comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)

    def _summed(self, gathered: tuple, shape: tuple[int, ...]) -> np.ndarray:
        """The cell values of a piecewise-constant form, ``gathered`` = (form, its vector), summed
        over the mesh (collective)."""
        form, b = gathered
        with b.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return self.comm.allreduce(b.array_r.reshape(-1, *shape).sum(axis=0), op=MPI.SUM)

    def gradient(self) -> np.ndarray:
        """dE/dc (n,), on every rank (collective)."""
        return self._summed(self._gradient, (len(self.dofs),))

    def hessian(self) -> np.ndarray:
        """d2E/dc2 (n, n), on every rank (collective)."""
        n = len(self.dofs)
        H = self._summed(self._hessian, (n, n))
        return 0.5 * (H + H.T)  # symmetric but for round-off

    def mixed_vectors(self) -> list:
        """d2E/(dq0 dc_j) for each j: PETSc vectors of q0's owned layout (collective)."""
        M = self._mixed_matrix
        M.zeroEntries()
        compat.assemble_matrix(M, self._mixed, [])
        M.assemble()
        out = []
        for e in self._components:
            v = M.createVecRight()
            M.multTranspose(e, v)
            out.append(v)
        return out


class CouplingGroup:
    """Several :class:`DofCoupling` s of distinct parameters acting as one (a shell tied at both
    of its ends): their energies add, their parameters are listed one coupling after the other,
    and no energy depends on another's parameters, so the Hessian is block diagonal."""

    def __init__(self, couplings):
        self.couplings = list(couplings)
        if not self.couplings:
            raise ValueError("a coupling group needs at least one coupling")
        self.dofs = np.concatenate([c.dofs for c in self.couplings])
        self.owned = np.concatenate([c.owned for c in self.couplings])
        self.global_dofs = np.concatenate([c.global_dofs for c in self.couplings])
        if len(np.unique(self.global_dofs)) != len(self.global_dofs):
            raise ValueError("a coupling group's couplings must not share a parameter")
        self.cells = np.unique(np.concatenate([c.cells for c in self.couplings]))
        self.residual0 = sum((c.residual0 for c in self.couplings[1:]), self.couplings[0].residual0)
        self.jacobian0 = sum((c.jacobian0 for c in self.couplings[1:]), self.couplings[0].jacobian0)

    def read(self) -> None:
        for c in self.couplings:
            c.read()

    def gradient(self) -> np.ndarray:
        return np.concatenate([c.gradient() for c in self.couplings])

    def hessian(self) -> np.ndarray:
        n = len(self.dofs)
        H, start = np.zeros((n, n)), 0
        for c in self.couplings:
            k = len(c.dofs)
            H[start : start + k, start : start + k] = c.hessian()
            start += k
        return H

    def mixed_vectors(self) -> list:
        return [v for c in self.couplings for v in c.mixed_vectors()]

    def energy(self) -> float:
        """The couplings' energy [J] at the current states (collective)."""
        self.read()
        return sum(c._scalar(c.energy) for c in self.couplings)


class JointState:
    """The states of both blocks as one, for :class:`~tapecoil.core.stepping.Continuation`
    (which saves a converged state and returns to it)."""

    def __init__(self, *functions):
        self.functions = functions

    def snapshot(self) -> np.ndarray:
        return np.concatenate([f.x.array for f in self.functions])

    def restore(self, saved: np.ndarray) -> None:
        start = 0
        for f in self.functions:
            n = len(f.x.array)
            f.x.array[:] = saved[start : start + n]
            start += n


class CoupledSNESSolver:
    """Newton for two :class:`Block` s joined by a :class:`DofCoupling` or a :class:`CouplingGroup`
    (see the module).

    ``prefix``, ``options``, ``rtol``, ``atol``, ``max_it``: as
    :class:`~tapecoil.core.newton.SNESSolver`'s; the command line's options under the prefix win.
    """

    def __init__(
        self,
        blocks,
        coupling: DofCoupling | CouplingGroup,
        *,
        prefix,
        options=None,
        rtol=1e-8,
        atol=1e-10,
        max_it=25,
    ):
        check_prefix(prefix)
        if len(blocks) != 2:
            raise ValueError(f"a coupled solve takes two blocks, got {len(blocks)}")
        self.blocks = blocks
        self.coupling = coupling
        first, second = blocks
        self.F_forms = [jit.form(first.F + coupling.residual0), jit.form(second.F)]
        self.J_forms = [jit.form(first.J + coupling.jacobian0), jit.form(second.J)]
        self.b = [compat.create_vector(blk.q.function_space) for blk in blocks]
        comm = first.q.function_space.mesh.comm
        self.comm = comm
        self.timings = {"residual": 0.0, "jacobian": 0.0, "solve": 0.0, "iterations": 0}

        # the rows of the first block that the coupling touches: the dofs of the cells its
        # integrals see; every Jacobian sets all of them, zeros too, so the pattern is fixed
        self._rows = self._coupled_rows()
        self.J, self.index_sets = self._joint_matrix()
        self._row_start = self.J.getOwnershipRange()[0]
        self._local_sets = self._set_local_numbering()
        self._coupled = self._joint_indices(coupling.global_dofs)
        self.x = self.J.createVecRight()
        self.r = self.J.createVecRight()

        scale = self.x.duplicate()
        scale.set(0.0)
        for blk, iset in zip(blocks, self.index_sets, strict=True):
            if blk.state_scale is not None:
                sub = scale.getSubVector(iset)
                sub.array[:] = blk.state_scale.x.array[: sub.getLocalSize()]
                scale.restoreSubVector(iset, sub)
        self.convergence = ResidualTest(scale.array.copy())
        scale.destroy()

        self.prefix = prefix
        self.options = {**DEFAULT_PETSC_OPTIONS, **(options or {})}
        # terms assembled beyond the forms (contact between the two blocks' surfaces), as
        # SNESSolver's: add_residual(r), add_jacobian(J) on the joint vector and matrix, begin()
        # before a solve, and an applied part through apply_coupling (see numbering())
        self.terms: list = []
        self._operator = None
        self.snes = create_snes(
            comm,
            prefix,
            self.options,
            (self._residual, self.r),
            (self._jacobian, self.J),
            (rtol, atol, max_it),
            self.convergence,
        )

    # --- the coupling's blocks
    def _coupled_rows(self) -> np.ndarray:
        """Owned, unconstrained rows of the first block that the coupling's integrals touch."""
        V0 = self.blocks[0].q.function_space
        cells = np.asarray(self.coupling.cells, dtype=np.int32)
        dofs = np.unique(np.asarray(V0.dofmap.list)[cells].reshape(-1))
        bs = V0.dofmap.index_map_bs
        rows = (dofs[:, None] * bs + np.arange(bs)).reshape(-1)
        rows = rows[rows < owned_size(V0)]
        return np.setdiff1d(rows, owned_constrained_dofs(V0, self.blocks[0].bcs)).astype(PETSc.IntType)

    def _joint_matrix(self):
        """The joint AIJ matrix with every entry any Jacobian sets (the blocks' form patterns,
        the coupled rows against the coupled dofs and back, the coupled dofs' n x n), and the
        global index sets of the two blocks in it (collective)."""
        blocks, comm = self.blocks, self.comm
        A = [dolfinx.fem.petsc.create_matrix(J) for J in self.J_forms]
        for matrix, J in zip(A, self.J_forms, strict=True):
            matrix.zeroEntries()
            compat.assemble_matrix(matrix, J, [])
            matrix.assemble()
        cp = self.coupling
        c = len(cp.dofs)
        A[1].setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        rows = cp.global_dofs[cp.owned]
        if len(rows):
            A[1].setValues(rows, cp.global_dofs, np.zeros((len(rows), c)), addv=PETSc.InsertMode.ADD_VALUES)
        A[1].assemble()
        n0, n1 = (owned_size(blk.q.function_space) for blk in blocks)
        N0, N1 = (global_size(blk.q.function_space) for blk in blocks)
        C = PETSc.Mat().createAIJ(((n0, N0), (n1, N1)), nnz=(c, c), comm=comm)
        C.setUp()
        start = C.getOwnershipRange()[0]
        for row in self._rows:
            C.setValues([start + row], cp.global_dofs, np.zeros(c), addv=PETSc.InsertMode.INSERT_VALUES)
        C.assemble()
        CT = C.transpose(PETSc.Mat())  # without a target, petsc4py transposes in place
        nest = PETSc.Mat().createNest([[A[0], C], [CT, A[1]]], comm=comm)
        index_sets = nest.getNestISs()[0]
        J = nest.convert("aij", PETSc.Mat())  # without a target, petsc4py converts in place
        for matrix in (nest, C, CT, *A):
            matrix.destroy()
        J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        return J, index_sets

    def _rank_starts(self, block: int) -> tuple[np.ndarray, np.ndarray]:
        """For every rank, its first row of the block ``block`` (0 or 1) in the joint matrix and
        its first dof in that block's own global numbering (collective)."""
        firsts, starts = block_row_starts([blk.q.function_space for blk in self.blocks], self.comm)
        return firsts[block], starts[block]

    def _joint_indices(self, second: np.ndarray) -> np.ndarray:
        """Global rows of the joint matrix of dofs of the second block given by their global
        indices in that block (collective)."""
        firsts, starts = self._rank_starts(1)
        owner = np.searchsorted(starts, second, side="right") - 1
        return (firsts[owner] + second - starts[owner]).astype(PETSc.IntType)

    def numbering(self) -> Numbering:
        """Where each block's unknowns sit in the joint vector and matrix, with each block's
        Dirichlet conditions (:class:`~tapecoil.core.numbering.Numbering`; collective)."""
        return joint_numbering([(blk.q.function_space, blk.bcs) for blk in self.blocks], self.comm)

    def _set_local_numbering(self) -> list:
        """Give the joint matrix a local numbering, each block's local dofs (owned, then ghosts,
        one index per dof) after the other, and return each block's local index set in it, for
        the forms' assembly through local references (collective)."""
        to_global, local_sets, offset = [], [], 0
        for k, blk in enumerate(self.blocks):
            V = blk.q.function_space
            index_map, bs = V.dofmap.index_map, V.dofmap.index_map_bs
            firsts, starts = self._rank_starts(k)
            owners = np.asarray(index_map.owners)
            ghost_rows = firsts[owners] + bs * np.asarray(index_map.ghosts) - starts[owners]
            owned_rows = firsts[self.comm.rank] + np.arange(owned_size(V))
            rows = np.concatenate([owned_rows, (ghost_rows[:, None] + np.arange(bs)).reshape(-1)])
            to_global.append(rows)
            local_sets.append(PETSc.IS().createStride(len(rows), offset, 1, comm=MPI.COMM_SELF))
            offset += len(rows)
        lgmap = PETSc.LGMap().create(np.concatenate(to_global).astype(PETSc.IntType), comm=self.comm)
        self.J.setLGMap(lgmap, lgmap)
        lgmap.destroy()
        return local_sets

    # --- SNES callbacks
    def _update_states(self, x) -> None:
        for blk, iset in zip(self.blocks, self.index_sets, strict=True):
            sub = x.getSubVector(iset)
            qv = blk.q.x.petsc_vec
            qv.array[:] = sub.array_r
            x.restoreSubVector(iset, sub)
            qv.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        self.coupling.read()

    def _write_states(self, x) -> None:
        for blk, iset in zip(self.blocks, self.index_sets, strict=True):
            sub = x.getSubVector(iset)
            sub.array[:] = blk.q.x.petsc_vec.array_r
            x.restoreSubVector(iset, sub)

    def _assemble_blocks(self, conditions: bool) -> None:
        """Each block's residual at the present states into ``self.b``: with its Dirichlet
        conditions (``conditions``; the residual on a held dof is q - g) or without them."""
        cp = self.coupling
        gradient = cp.gradient()
        for k, (blk, b) in enumerate(zip(self.blocks, self.b, strict=True)):
            extra = None
            if k == 1:

                def extra(local, g=gradient):
                    local[cp.dofs[cp.owned]] += g[cp.owned]

            bcs = blk.bcs if conditions else []
            assemble_residual(b, self.F_forms[k], self.J_forms[k], bcs, blk.q, [], blk.point_forces, extra)

    def _residual(self, _snes, x, r) -> None:
        t0 = time.perf_counter()
        self._update_states(x)
        self._assemble_blocks(conditions=True)
        for k, b in enumerate(self.b):
            sub = r.getSubVector(self.index_sets[k])
            sub.array[:] = b.array_r
            r.restoreSubVector(self.index_sets[k], sub)
        for term in self.terms:
            term.add_residual(r)
        self.timings["residual"] += time.perf_counter() - t0

    def free_residuals(self) -> list[np.ndarray]:
        """Each block's residual at the present states without its Dirichlet conditions, on its
        owned dofs (collective): on a held dof, the force the condition supplies (the support's
        reaction, at the levels the solve's equations hold at)."""
        self.coupling.read()
        self._assemble_blocks(conditions=False)
        return [b.array_r.copy() for b in self.b]

    def _jacobian(self, _snes, x, J, P) -> None:
        t0 = time.perf_counter()
        self._update_states(x)
        cp = self.coupling
        P.zeroEntries()
        for blk, J_form, local in zip(self.blocks, self.J_forms, self._local_sets, strict=True):
            block = P.getLocalSubMatrix(local, local)
            compat.assemble_matrix_local(block, J_form, blk.bcs)
            P.restoreLocalSubMatrix(local, local, block)
        P.assemble(PETSc.Mat.AssemblyType.FLUSH)  # from adding to inserting
        for blk, J_form, local in zip(self.blocks, self.J_forms, self._local_sets, strict=True):
            block = P.getLocalSubMatrix(local, local)
            compat.insert_diagonal(block, J_form, blk.bcs)
            P.restoreLocalSubMatrix(local, local, block)
        P.assemble(PETSc.Mat.AssemblyType.FLUSH)
        add = PETSc.InsertMode.ADD_VALUES
        H = cp.hessian()
        if cp.owned.any():
            P.setValues(self._coupled[cp.owned], self._coupled, H[cp.owned], addv=add)
        vectors = cp.mixed_vectors()
        values = np.column_stack([v.array_r[self._rows] for v in vectors])
        for v in vectors:
            v.destroy()
        if len(self._rows):
            rows = (self._row_start + self._rows).astype(PETSc.IntType)
            P.setValues(rows, self._coupled, values, addv=add)
            P.setValues(self._coupled, rows, np.ascontiguousarray(values.T), addv=add)
        P.assemble()
        widened = [term.add_jacobian(P) for term in self.terms]
        P.assemble()
        if J.handle != P.handle:
            J.assemble()
        self.convergence.update_floor(P, x)
        if any(widened):
            # a widened pattern replaces the matrix's storage, which the factorisation does
            # not notice (as SNESSolver's)
            self.snes.getKSP().getPC().reset()
        self.timings["jacobian"] += time.perf_counter() - t0

    def _use_operator(self) -> None:
        if self._operator is None and any(hasattr(term, "apply_coupling") for term in self.terms):
            operator = JacobianOperator(lambda: self.J, lambda: self.terms)
            J = PETSc.Mat().createPython(self.J.getSizes(), operator, comm=self.J.getComm())
            J.setUp()
            self.snes.setJacobian(self._jacobian, J, self.J)
            self._operator = J

    def _renew_matrix(self) -> None:
        """Start the joint matrix again from the blocks' and the ties' pattern (collective)."""
        old = self.J
        self.J, _ = self._joint_matrix()
        self._local_sets = self._set_local_numbering()
        self.snes.setJacobian(self._jacobian, self.J if self._operator is None else self._operator, self.J)
        self.snes.getKSP().getPC().reset()
        old.destroy()

    def solve(self) -> SolveResult:
        """Solve from the current states; on failure they hold the last iterate."""
        self._use_operator()
        if any([term.begin() for term in self.terms]):  # a list: every term's begin() runs
            self._renew_matrix()
        self._write_states(self.x)
        result = run_snes(self.snes, self.x, self.prefix, self.options, self.timings)
        if result.converged:
            self._update_states(self.x)
        return result

    def destroy(self) -> None:
        for obj in (self.snes, self.J, self.x, self.r, *self.b, *self._local_sets, self._operator):
            if obj is not None:
                obj.destroy()
