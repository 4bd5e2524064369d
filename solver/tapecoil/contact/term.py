"""The self-contact's force and Newton matrix in a Newton solver of one or several blocks.

The solver calls the term at every residual and Jacobian (its ``terms``); the contact couples
dofs of distant parts of the mesh, so the matrix's nonzero pattern is widened when new pairs
appear (:meth:`SelfContactTerm.add_jacobian`). Where the solver's unknowns sit is a
:class:`Numbering`: one block's dofs as they are (:func:`block_numbering`, a shell's solver), or
several blocks' in a joint vector (a coupled solver's). A surface whose nodes are carried by
rotations (a beam's strip) has its pairs' forces and matrices taken to the rotations by the
chain rule: dx = du + A dtheta, A = dx/dtheta, and Newton's matrix gains the force times
d2x/dtheta2 (:meth:`~tapecoil.contact.surface.ContactSurface.rotation_hessian`).
"""

from __future__ import annotations

import time

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil.contact import kernels
from tapecoil.contact.self_contact import ContactPairs, SelfContact
from tapecoil.core.numbering import Numbering, block_numbering

__all__ = [
    "SOLVER_OPTIONS",
    "Numbering",
    "PairsAtState",
    "SelfContactTerm",
    "add_blocks",
    "block_numbering",
    "linear_solver_options",
]


class PairsAtState:
    """The contact pairs of one state, kept while that state and the converged one are unchanged.

    The decision is collective: :meth:`SelfContact.pairs` gathers positions from every rank,
    so every rank must agree to compute them again, also when only some ranks' dofs changed.
    """

    def __init__(self, contact: SelfContact):
        self.contact = contact
        self.clear()

    def clear(self) -> None:
        self._q = self._version = self._pairs = None

    def get(self, q: np.ndarray, compute) -> ContactPairs:
        """The pairs at the state ``q`` (the blocks' arrays one after the other): kept ones, or
        ``compute()`` (collective)."""
        same = (
            self._q is not None
            and self._version == self.contact._reference_version
            and np.array_equal(self._q, q)
        )
        if self.contact.comm.allreduce(int(not same), op=MPI.MAX):
            self._pairs = compute()
            self._q, self._version = q.copy(), self.contact._reference_version
        return self._pairs


# Newton's linear systems with the self-contact. The exact Jacobian is the assembled matrix
# (the shell, the hub and each pair's force on its own 30 dofs) plus the pairs' dependence on
# the nodal normals, on each partner cell's patch of up to 49 nodes: assembled, that part would
# be 30 x 147 entries a pair and widen the factorisation. It is applied instead, exactly, in a
# GMRES preconditioned by the factorised assembled matrix. The force along the partner's
# smoothed normal is not the gradient of an energy, so neither matrix is symmetric: LU, not
# MUMPS' LDL^T. PETSc's divergence test (1e4 times the first residual) stays: without it a
# step of the default-mesh coiling whose Newton runs away goes on for minutes, its memory
# growing, where the test cuts the step back and the run goes on (docs/notes/coiling.md)
SOLVER_OPTIONS = {
    "pc_type": "lu",
    "ksp_type": "gmres",
    "ksp_rtol": 1e-8,
    "ksp_max_it": 100,
}


def linear_solver_options(self_contact: bool) -> dict:
    """The linear solve of a Newton solver whose Jacobian is a Hessian (energies, penalty contact
    with the hub or the spiral, dead loads, the hybrid's ties) unless ``self_contact`` adds the
    turns' real contact: MUMPS' LDL^T for a Hessian, else :data:`SOLVER_OPTIONS` (LU of the
    assembled part, the applied part in GMRES). PETSc option names without prefix."""
    return dict(SOLVER_OPTIONS) if self_contact else {"pc_type": "cholesky"}


def add_blocks(A: PETSc.Mat, dofs: np.ndarray, blocks: np.ndarray) -> None:
    """Add square blocks (P, n, n) on the global rows and columns ``dofs`` (P, n) to ``A``, all
    in one call (rows owned by other ranks go through PETSc's stash; negative indices, the
    constrained dofs, are left out as MatSetValues leaves them)."""
    P, n = dofs.shape
    if P == 0:
        return
    rows = np.ascontiguousarray(dofs, dtype=PETSc.IntType).ravel()
    columns = np.repeat(dofs[:, None, :], n, axis=1).astype(PETSc.IntType).ravel()
    starts = np.arange(0, P * n * n + 1, n, dtype=PETSc.IntType)
    A.setValuesIJV(
        starts,
        columns,
        np.ascontiguousarray(blocks, dtype=float).ravel(),
        addv=PETSc.InsertMode.ADD,
        rowmap=rows,
    )


class SelfContactTerm:
    """The self-contact's force and matrix in a Newton solver (its ``terms``).

    ``numbering``: where the surface's unknowns sit in the solver (:class:`Numbering`). The force
    enters as ``weight`` f(x) and, with ``previous = (weight_old, state_old)`` (``state_old``: the
    blocks' Functions at the old state), plus weight_old f(x_old): the force average of
    generalized-alpha.
    """

    def __init__(self, contact: SelfContact, numbering: Numbering, weight: float = 1.0, previous=None):
        self.contact, self.numbering = contact, numbering
        surface = contact.surface
        unknowns = surface.unknowns()
        self.u_rows = numbering.map(unknowns.block, unknowns.u).astype(PETSc.IntType)
        self.theta_rows = numbering.map(unknowns.block, unknowns.theta).astype(PETSc.IntType)
        # the rows a node's position moves: its displacement's, and its rotation's if carried
        self.node_rows = (
            np.concatenate([self.u_rows, self.theta_rows], axis=1) if surface.carried else self.u_rows
        )
        self.weight, self.previous = weight, previous
        self.search, self.search_previous = contact.new_search(), contact.new_search()
        self._kept = {"current": PairsAtState(contact), "previous": PairsAtState(contact)}
        self._pattern: set[int] = set()
        self._memory = np.full(2 * contact.n_nodes, -1, dtype=np.int64)
        self._converged_version = -1
        self._coupling = None
        self._live: set[int] = set()
        self.pattern_extensions = self.pattern_renewals = 0

    def _state(self, name: str) -> list[np.ndarray] | None:
        if name == "current":
            return None
        return [f.x.array for f in self.previous[1]]

    def _pairs(self, name: str) -> ContactPairs:
        state = self._state(name)
        key = np.concatenate(self.contact.surface.state() if state is None else state)
        search = self.search if name == "current" else self.search_previous
        memory = self._memory if name == "current" else None
        return self._kept[name].get(key, lambda: self.contact.pairs(search, memory, state))

    def begin(self) -> bool:
        """Before a solve: the partners kept are those of the last converged state, or none.

        A solve that follows a converged one takes the partners it ended with; a retry (after
        a failed solve, from the same converged state) keeps none and starts from the closest
        cells, as a run restarted from that state does: coarse-mesh deployments that stopped
        with every cut-back failing went on when restarted there, and go on unstopped so.
        Returns True (on every rank) when the matrix should start again from the solver's own
        pattern: the pairs in it that the last Jacobian no longer had outnumber those it had
        (collective). A coil's material runs through the ploy region and each node meets
        partner after partner; kept, their couplings tripled the matrix's nonzeros by 36 rad
        on the coarse benchmark, and every factorisation paid for them.
        """
        renew = False
        if self.contact._reference_version != self._converged_version:
            self._converged_version = self.contact._reference_version
            stale = len(self._pattern - self._live)
            counts = self.contact.comm.allreduce(np.array([stale, len(self._live)]), op=MPI.SUM)
            renew = bool(counts[0] > max(counts[1], 1))
            if renew:
                self._pattern.clear()
                self.pattern_renewals += 1
        else:
            self._memory[:] = -1
        for kept in self._kept.values():
            kept.clear()
        return renew

    def current(self) -> ContactPairs:
        return self._pairs("current")

    def seconds(self) -> float:
        """The wall time this term's contact has spent [s]: its search, its pairs' forces and
        matrices, the nodal normals' part applied in the Krylov solve (and the pairs that the
        run's measures asked of the same contact)."""
        return float(sum(self.contact.timings.values()))

    def _pair_nodes(self, pairs: ContactPairs) -> np.ndarray:
        """The node and the partner cell's nodes of each pair (P, 10)."""
        return np.concatenate([pairs.node[:, None], self.contact.cells[pairs.cell]], axis=1)

    def _pair_rows(self, pairs: ContactPairs) -> np.ndarray:
        """The solver rows of each pair's nodes (P, 10 x 3, or 10 x 6 with rotations)."""
        return self.node_rows[self._pair_nodes(pairs)].reshape(len(pairs.node), 10 * self.node_rows.shape[1])

    def _to_unknowns(self, pairs: ContactPairs, values: np.ndarray, jacobian) -> np.ndarray:
        """Pair values on the nodes' positions (P, 30) as values on their unknowns: as they are,
        or, on a surface carried by rotations, each node's (v, A^T v) (P, 60)."""
        if jacobian is None:
            return values
        P = len(values)
        v = values.reshape(P, 10, 3)
        turned = np.einsum("pnij,pni->pnj", jacobian[self._pair_nodes(pairs)], v)
        return np.concatenate([v, turned], axis=2).reshape(P, 60)

    def _jacobian_at(self, name: str):
        """dx/dtheta (N, 3, 3) of the surface at the current or the old state (None: no rotation
        carries it)."""
        surface = self.contact.surface
        return surface.unknowns(self._state(name)).jacobian if surface.carried else None

    def add_residual(self, b: PETSc.Vec) -> None:
        """Add the contact force to the residual vector ``b`` (collective)."""
        names = ["current"] + (["previous"] if self.previous is not None else [])
        parts = [(self.weight if name == "current" else self.previous[0], name) for name in names]
        t0 = time.perf_counter()
        for weight, name in parts:
            pairs = self._pairs(name)
            values = self._to_unknowns(
                pairs, (weight * pairs.force)[:, None] * pairs.B, self._jacobian_at(name)
            )
            rows = self._pair_rows(pairs).ravel()
            values = values.ravel()
            free = rows >= 0  # a vector, unlike a matrix, takes no negative index
            b.setValues(rows[free], values[free], addv=PETSc.InsertMode.ADD)
        b.assemblyBegin()
        b.assemblyEnd()
        self.contact.timings["assembly"] += time.perf_counter() - t0

    def add_jacobian(self, A: PETSc.Mat) -> bool:
        """Add the contact matrix to ``A`` (collective); True if A's pattern had to be widened.

        A takes each pair's force differentiated on its own nodes' unknowns; its derivative
        through the nodal normals, on the nodes around the partner cell, is kept for
        :meth:`apply_coupling`.
        """
        pairs = self.current()
        matrix, sensitivity = self.contact.jacobian_blocks(pairs)
        jacobian = self._jacobian_at("current")
        self._coupling = (pairs, sensitivity, self.contact.normal_derivatives(pairs), jacobian)
        t0 = time.perf_counter()
        keys = pairs.node * len(self.contact.cells) + pairs.cell
        listed = keys.tolist()
        self._live = set(listed)
        new = np.array([k not in self._pattern for k in listed], dtype=bool)
        rows = self._pair_rows(pairs)
        A.assemble()
        widen = self.contact.comm.allreduce(int(new.sum()), op=MPI.SUM) > 0
        if widen:
            self._widen(A, rows[new])
            self._pattern.update(keys[new].tolist())
        if jacobian is None:
            add_blocks(A, rows, self.weight * matrix)
        else:
            blocks = kernels.chain_blocks(self._pair_nodes(pairs), jacobian, matrix)
            add_blocks(A, rows, self.weight * blocks)
            # the force on each carried point times its position's second derivative in the
            # rotation: on the rotation's own dofs, within the solver's pattern
            forces = self.contact.nodal_forces(pairs)
            hessian = self.contact.surface.rotation_hessian(forces)
            carried = np.flatnonzero(np.abs(forces).sum(axis=1) > 0)
            add_blocks(A, self.theta_rows[carried], self.weight * hessian[carried])
        self.contact.timings["assembly"] += time.perf_counter() - t0
        return widen

    def apply_coupling(self, x: PETSc.Vec, y: PETSc.Vec, transpose: bool = False) -> None:
        """y += K x (or K^T x), K the part of the Jacobian at the last :meth:`add_jacobian` that
        goes through the nodal normals (collective). Constrained dofs take no part."""
        t0 = time.perf_counter()
        pairs, sensitivity, D, jacobian = self._coupling
        contact = self.contact
        # the constrained dofs' values do not move the surface (their rows are the solver's)
        values = contact.surface.values(self.numbering.free(x))
        neighbourhood = contact.normal_field.neighbourhood
        if not transpose:
            out = kernels.apply_normals(
                pairs.cell, contact.cells, pairs.N, sensitivity, neighbourhood, D, values, False
            )
            out = self._to_unknowns(pairs, out, jacobian)
            rows = self._pair_rows(pairs).ravel()
        else:
            on_rows = values[self._pair_nodes(pairs)].reshape(len(pairs.node), 30)
            out = kernels.apply_normals(
                pairs.cell, contact.cells, pairs.N, sensitivity, neighbourhood, D, on_rows, True
            )
            if jacobian is not None:
                out = np.concatenate([out, np.einsum("nij,ni->nj", jacobian, out)], axis=1)
            rows = self.node_rows.ravel()
        out = self.weight * out.ravel()
        free = (rows >= 0) & (out != 0.0)
        y.setValues(rows[free], out[free], addv=PETSc.InsertMode.ADD)
        y.assemblyBegin()
        y.assemblyEnd()
        contact.timings["coupling"] += time.perf_counter() - t0

    def _widen(self, A: PETSc.Mat, dofs: np.ndarray) -> None:
        """Add the couplings of the pairs ``dofs`` (P, 30) to A's nonzero pattern (collective).

        The couplings go into a matrix C of zeros (PETSc's stash takes the rows other ranks own),
        and A + C with a different pattern builds the union pattern with its exact preallocation
        in one pass, instead of a reallocation of A for each row that gains an entry. C itself
        is preallocated from the couplings counted row by row (summed over the ranks, so an
        upper bound where two ranks' pairs share a row): grown entry by entry instead, a
        widening by all the pairs of the default-mesh benchmark's coil took 18.7 s, against
        0.15 s for the Jacobian it served.
        """
        comm = self.contact.comm
        n = A.getSize()[0]
        width = dofs.shape[1]
        rows = np.repeat(dofs, width, axis=1).ravel().astype(np.int64)
        cols = np.tile(dofs, (1, width)).ravel().astype(np.int64)
        used = (rows >= 0) & (cols >= 0)
        key = np.unique(rows[used] * n + cols[used])
        rows, cols = key // n, key % n
        ranges = np.asarray(A.getOwnershipRanges(), dtype=np.int64)
        owner = np.searchsorted(ranges, rows, side="right") - 1
        diagonal = (cols >= ranges[owner]) & (cols < ranges[owner + 1])
        counts = np.zeros((2, n), dtype=np.int64)
        counts[0] = np.bincount(rows[diagonal], minlength=n)
        counts[1] = np.bincount(rows[~diagonal], minlength=n)
        comm.Allreduce(MPI.IN_PLACE, counts, op=MPI.SUM)
        start, stop = A.getOwnershipRange()
        local_columns = stop - start
        d_nnz = np.minimum(counts[0, start:stop], local_columns).astype(PETSc.IntType)
        o_nnz = np.minimum(counts[1, start:stop], n - local_columns).astype(PETSc.IntType)
        C = PETSc.Mat().create(A.getComm())
        C.setSizes(A.getSizes())
        C.setType(PETSc.Mat.Type.AIJ)
        C.setPreallocationNNZ((d_nnz, o_nnz))
        C.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        add_blocks(C, dofs, np.zeros((len(dofs), width, width)))
        C.assemble()
        lgmaps = A.getLGMap()
        A.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        A.setLGMap(*lgmaps)
        C.destroy()
        self.pattern_extensions += 1
