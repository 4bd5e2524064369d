"""Where a solver's unknowns sit: one block's dofs as they are, or several blocks' in a joint
vector, with the rows their Dirichlet conditions hold (:class:`Numbering`).

A term assembled beside a solver's forms (the contact between surfaces, which touches dofs of
any block) writes into the solver's vector and matrix by these rows.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from tapecoil.core.dofs import owned_constrained_dofs

__all__ = ["Numbering", "block_numbering", "constrained_global"]


@dataclass
class Numbering:
    """Where a contact surface's blocks of unknowns sit in a solver (collective to build).

    ``rows[k](dofs)``: the solver's global rows of block k's global dofs ``dofs``;
    ``constrained[k]``: block k's globally numbered dofs that Dirichlet conditions hold (they
    take no contact entries: the solver sets their rows), ``constrained_local[k]`` the same as
    this rank's owned local indices; ``owned(vector)``: each block's owned values of a solver
    vector, in the block's own layout.
    """

    rows: list[Callable[[np.ndarray], np.ndarray]]
    constrained: list[np.ndarray]
    constrained_local: list[np.ndarray]
    owned: Callable[[PETSc.Vec], list[np.ndarray]]

    def free(self, vector: PETSc.Vec) -> list[np.ndarray]:
        """Each block's owned values of ``vector`` (copies), those of constrained dofs zeroed."""
        out = [v.copy() for v in self.owned(vector)]
        for values, local in zip(out, self.constrained_local, strict=True):
            values[local] = 0.0
        return out

    def map(self, block: np.ndarray, dofs: np.ndarray) -> np.ndarray:
        """Solver rows (same shape as ``dofs``) of the dofs ``dofs`` of the blocks ``block`` (one
        per row of ``dofs``); -1 where constrained or absent (a negative dof)."""
        out = np.full(dofs.shape, -1, dtype=np.int64)
        for k, (to_rows, fixed) in enumerate(zip(self.rows, self.constrained, strict=True)):
            mine = (block == k)[:, None] & (dofs >= 0)
            if mine.any():
                free = mine & ~np.isin(dofs, fixed)
                out[free] = to_rows(dofs[free])
        return out


def constrained_global(V, bcs) -> np.ndarray:
    """The dofs of V (global numbering) that the Dirichlet conditions ``bcs`` hold, on every rank
    (collective)."""
    index_map, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    owned = owned_constrained_dofs(V, bcs)
    glob = index_map.local_to_global((owned // bs).astype(np.int32)) * bs + owned % bs
    return np.unique(np.concatenate(V.mesh.comm.allgather(glob.astype(np.int64))))


def block_numbering(V, bcs) -> Numbering:
    """One block's unknowns as they are (a solver of the Function space V alone, e.g. a
    :class:`~tapecoil.core.newton.SNESSolver`) with its Dirichlet conditions ``bcs``."""
    return Numbering(
        [lambda dofs: dofs],
        [constrained_global(V, bcs)],
        [owned_constrained_dofs(V, bcs)],
        lambda v: [v.getArray(readonly=True)],
    )


def block_row_starts(spaces, comm) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """For blocks of unknowns in the Function spaces ``spaces`` joined in one vector, each rank's
    owned dofs of the first block, then of the second, ...: for each block and every rank, the
    rank's first row of the block in the joint vector and its first dof in the block's own
    global numbering (collective)."""
    owned = np.array([V.dofmap.index_map.size_local * V.dofmap.index_map_bs for V in spaces], dtype=np.int64)
    every = np.array(comm.allgather(owned))  # (ranks, blocks)
    rank_start = np.concatenate([[0], np.cumsum(every.sum(axis=1))[:-1]])
    firsts, starts = [], []
    for k, V in enumerate(spaces):
        firsts.append(rank_start + every[:, :k].sum(axis=1))
        first_dof = V.dofmap.index_map_bs * V.dofmap.index_map.local_range[0]
        starts.append(np.array(comm.allgather(first_dof), dtype=np.int64))
    return firsts, starts


def joint_numbering(blocks, comm) -> Numbering:
    """Blocks of unknowns ``blocks`` = [(V, bcs), ...] (Function spaces and their Dirichlet
    conditions) joined in one vector as :func:`block_row_starts` lays them out (a
    :class:`~tapecoil.core.coupled_newton.CoupledSNESSolver`'s; collective)."""
    spaces = [V for V, _ in blocks]
    firsts, starts = block_row_starts(spaces, comm)
    rows = []
    for first, start in zip(firsts, starts, strict=True):

        def to_rows(dofs, first=first, start=start):
            owner = np.searchsorted(start, dofs, side="right") - 1
            return first[owner] + dofs - start[owner]

        rows.append(to_rows)
    sizes = np.cumsum([0] + [V.dofmap.index_map.size_local * V.dofmap.index_map_bs for V in spaces])

    def owned(vector) -> list[np.ndarray]:
        values = vector.getArray(readonly=True)
        return [values[a:b] for a, b in itertools.pairwise(sizes)]

    return Numbering(
        rows,
        [constrained_global(V, bcs) for V, bcs in blocks],
        [owned_constrained_dofs(V, bcs) for V, bcs in blocks],
        owned,
    )
