"""Distributed dof bookkeeping: owned sizes, global sums and norms, node and cell values,
vectors assembled with their ghosts' contributions.

Every function here is collective where it says so and rank-local otherwise; none assumes that
any rank owns any particular dof.
"""

from __future__ import annotations

import math

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.core import compat, jit
from tapecoil.core.expression import expression_at


def owned_size(V) -> int:
    """Number of dofs (blocks unrolled) this rank owns in the space V."""
    return V.dofmap.index_map.size_local * V.dofmap.index_map_bs


def global_size(V) -> int:
    """Number of dofs (blocks unrolled) of the space V over all ranks."""
    return V.dofmap.index_map.size_global * V.dofmap.index_map_bs


def global_scalar(form, comm) -> float:
    """A scalar form (UFL or compiled) assembled and summed over all ranks of ``comm`` (collective)."""
    compiled = form if isinstance(form, dolfinx.fem.Form) else jit.form(form)
    return comm.allreduce(dolfinx.fem.assemble_scalar(compiled), op=MPI.SUM)


def global_dot(V, a: np.ndarray, b: np.ndarray) -> float:
    """Dot product over all ranks of the owned parts of two local dof arrays of the space V
    (collective)."""
    n = owned_size(V)
    return V.mesh.comm.allreduce(float(np.dot(a[:n], b[:n])), op=MPI.SUM)


def global_norm(V, local_values: np.ndarray) -> float:
    """Euclidean norm over all ranks of the owned part of a local dof array of the space V."""
    return math.sqrt(global_dot(V, local_values, local_values))


def owned_constrained_dofs(V, bcs) -> np.ndarray:
    """The owned dofs of V that the Dirichlet conditions ``bcs`` hold, local indices in the
    conditions' order (rank-local)."""
    local = [bc.dof_indices()[0] for bc in bcs]
    dofs = np.concatenate(local) if local else np.zeros(0, np.int32)
    return dofs[dofs < owned_size(V)]


def owned_subspace_dofs(V, sub: tuple[int, ...], dim: int, entities: np.ndarray) -> np.ndarray:
    """Owned dofs of the subspace ``V.sub(i).sub(j)...`` on mesh entities of dimension ``dim``.

    Indices into the local dof array of V; rank-local.
    """
    space = V
    for i in sub:
        space = space.sub(i)
    collapsed, _ = space.collapse()
    dofs = dolfinx.fem.locate_dofs_topological((space, collapsed), dim, entities)[0]
    return dofs[dofs < owned_size(V)]


def at_node(point):
    """A marker for ``locate_dofs_geometrical``: the parameter points at ``point`` (x, y), to
    1e-10 of its size."""
    p = np.asarray(point, dtype=float)

    def marker(x):
        return np.isclose(x[0], p[0], atol=1e-10 * (1 + abs(p[0]))) & np.isclose(
            x[1], p[1], atol=1e-10 * (1 + abs(p[1]))
        )

    return marker


def owned_node_dofs(V, sub: tuple[int, ...], point) -> np.ndarray:
    """Owned dofs of the (sub-)space ``V.sub(i).sub(j)...`` at the node at ``point`` (rank-local).

    Returns indices into the local dof array of V; empty on ranks that do not own the node.
    """
    space = V
    for i in sub:
        space = space.sub(i)
    collapsed, _ = space.collapse()
    dofs = dolfinx.fem.locate_dofs_geometrical((space, collapsed), at_node(point))[0]
    return dofs[dofs < owned_size(V)]


def assemble_into(function, form) -> np.ndarray:
    """Assemble the compiled vector ``form`` into the Function ``function`` from zero, the ghosts'
    contributions added to their owners (collective); returns its local array."""
    function.x.array[:] = 0.0
    dolfinx.fem.assemble_vector(function.x.array, form)
    function.x.scatter_reverse(dolfinx.la.InsertMode.add)
    return function.x.array


def node_value(q, sub: tuple[int, ...], point) -> float:
    """Value of a scalar component of q at a mesh node, on every rank (collective)."""
    dofs = owned_node_dofs(q.function_space, sub, point)
    comm = q.function_space.mesh.comm
    count = comm.allreduce(len(dofs))
    if count != 1:
        raise ValueError(f"expected one node at {point}, found {count}")
    return comm.allreduce(float(q.x.array[dofs].sum()))


def cell_midpoint_values(mesh, expressions):
    """Values of scalar UFL expressions at the midpoints of this rank's owned cells (rank-local).

    Returns the DG0 space and an array (n_owned_cells, gdim + len(expressions)): the cell
    midpoint's coordinates (the first two), then the values; row i is the space's local dof i.
    """
    V0 = dolfinx.fem.functionspace(mesh, ("DG", 0))
    n_owned = V0.dofmap.index_map.size_local
    coordinates = V0.tabulate_dof_coordinates()[:n_owned]
    columns = [coordinates[:, 0], coordinates[:, 1]]
    points = compat.interpolation_points(V0)
    for expr in expressions:
        f = dolfinx.fem.Function(V0)
        f.interpolate(expression_at(expr, points))
        columns.append(f.x.array[:n_owned].copy())
    return V0, np.column_stack(columns)
