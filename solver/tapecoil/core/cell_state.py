"""State on meshes a run builds again: values saved cell by cell, in the mesh's input order.

A model whose meshes are generated from its parameters (a hybrid's shell window and beams,
rebuilt wherever its window lies) need not store the meshes to be restarted: built again from
the same input, on any number of ranks, a mesh has the same cells in the same input order
(``topology.original_cell_index``), each with its vertices in the input's order, so a dof's
place in its cell is the same. A field is then saved as the values of each cell's dofs, in
the input order of the cells, and put back cell by cell (ghosts included, so no exchange is
needed). This covers any field on the cells' dofs: a Function of any element (Lagrange, DG,
quadrature points) and per-node arrays kept beside it in NumPy (a rotation per node, indexed
like a collapsed subspace's dofs).

adios4dolfinx's checkpoints carry their mesh, and its checkpoints on an input mesh take
Lagrange and DG Functions only; the hybrid's frames at quadrature points and its per-node
frames need the form here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CellField", "function_field", "gather_fields", "scatter_fields"]


@dataclass(frozen=True)
class CellField:
    """Values reached through a dofmap: ``values`` (a live array, one row per dof index of
    ``dofs``, a (local cells, dofs per cell) table such as ``V.dofmap.list``) on ``mesh``."""

    mesh: object
    dofs: np.ndarray
    values: np.ndarray

    def __post_init__(self):
        if self.values.ndim != 2:
            raise ValueError("a cell field's values are a 2-d array (dof, component)")


def function_field(function) -> CellField:
    """The dof values of a DOLFINx Function as a :class:`CellField` (a view: setting it sets them)."""
    dofmap = function.function_space.dofmap
    return CellField(
        function.function_space.mesh,
        np.asarray(dofmap.list),
        function.x.array.reshape(-1, dofmap.bs),
    )


def _owned_cells(mesh, numbering: str = "input") -> tuple[int, np.ndarray]:
    tdim = mesh.topology.dim
    index_map = mesh.topology.index_map(tdim)
    owned = index_map.size_local
    if numbering == "global":
        return index_map.size_global, np.arange(*index_map.local_range, dtype=np.int64)
    if numbering != "input":
        raise ValueError(f"cells are numbered 'input' or 'global', got {numbering!r}")
    return index_map.size_global, np.asarray(mesh.topology.original_cell_index[:owned], dtype=np.int64)


def gather_fields(fields: dict[str, CellField], comm, numbering: str = "input") -> dict[str, np.ndarray]:
    """Each field's values as (global cells, dofs per cell, components) in the cells' input
    order, on rank 0 (empty dict elsewhere; collective).

    ``numbering="global"``: in the order of the cells' global indices instead, the order in
    which adios4dolfinx writes a mesh, so that the mesh read back from that checkpoint, whose
    input order is the file's, takes them back with :func:`scatter_fields`."""
    out = {}
    for name, field in fields.items():
        size, original = _owned_cells(field.mesh, numbering)
        table = field.values[field.dofs[: len(original)]]
        pieces = comm.gather((original, table), root=0)
        if comm.rank == 0:
            width = field.values.shape[1]
            per_cell = field.dofs.shape[1]
            full = np.full((size, per_cell, width), np.nan)
            for index, values in pieces:
                full[index] = values.reshape(len(index), per_cell, width)
            if np.isnan(full).any():
                raise ValueError(f"cell state {name!r}: cells missing from the gathered field")
            out[name] = full
    return out


def scatter_fields(fields: dict[str, CellField], tables: dict[str, np.ndarray]) -> None:
    """Set each field from its table of :func:`gather_fields` (every rank holding the whole
    table), on all its local cells, ghosts included (rank-local)."""
    for name, field in fields.items():
        if name not in tables:
            raise KeyError(f"the saved state has no field {name!r}")
        table = tables[name]
        local = field.dofs.shape[0]
        original = np.asarray(field.mesh.topology.original_cell_index[:local], dtype=np.int64)
        expected = (field.dofs.shape[1], field.values.shape[1])
        cells = field.mesh.topology.index_map(field.mesh.topology.dim).size_global
        if table.shape != (cells, *expected):
            raise ValueError(
                f"cell state {name!r}: saved as {table.shape[0]} cells of {table.shape[1:]} values, "
                f"the rebuilt mesh has {cells} cells of {expected}: not the same model"
            )
        field.values[field.dofs.reshape(-1)] = table[original].reshape(-1, expected[1])
