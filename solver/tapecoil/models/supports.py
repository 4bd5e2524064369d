"""Supports of a shell edge or node beyond a clamp: a plane of symmetry, a point held.

Each returns the Dirichlet conditions, for a :class:`~tapecoil.models.problem.ShellProblem` or
any solver of a :class:`~tapecoil.models.shell.NaghdiShell` (local director frame).
"""

from __future__ import annotations

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.core.dofs import at_node
from tapecoil.models.edges import facet_condition

AXES = "xyz"


def _dof_points(model, facets: np.ndarray) -> np.ndarray:
    """Parameter points (2, n) of this rank's nodes on ``facets`` (some ranks hold none)."""
    V, _ = model.W.sub(0).sub(0).collapse()
    dofs = dolfinx.fem.locate_dofs_topological(V, 1, facets)
    return V.tabulate_dof_coordinates()[dofs, :2].T


def symmetry_plane(model, facets: np.ndarray, normal, edge: str = "the edge") -> list:
    """Conditions of a plane of symmetry with unit ``normal`` (a coordinate axis) on ``facets``.

    The displacement along the normal vanishes and the director stays in the plane. The plane
    must contain the edge and the shell's normal there, so that it is normal to one of the
    edge's tangents t1 or t2; then keeping the director in the plane is, exactly, the vanishing
    of the one director angle that tilts it towards that tangent (theta_0 towards t2, theta_1
    towards t1). Checked on every rank's nodes of the edge (collective); ValueError otherwise.
    """
    n = np.asarray(normal, dtype=float)
    axis = int(np.argmax(np.abs(n))) if n.size else 0
    if n.shape != (3,) or not np.isclose(abs(n[axis]), 1.0) or np.count_nonzero(n) != 1:
        raise ValueError(f"symmetry plane on {edge}: normal {tuple(n)} must be +-x, +-y or +-z")
    comm = model.mesh.comm
    surface = model.strip.geometry
    xi = _dof_points(model, facets)
    X = surface.phi0(xi) if xi.size else np.zeros((3, 0))
    t1, t2, _ = surface.frame(xi) if xi.size else (np.zeros((3, 0)),) * 3
    lo = comm.allreduce(X[axis].min(initial=np.inf), op=MPI.MIN)
    hi = comm.allreduce(X[axis].max(initial=-np.inf), op=MPI.MAX)
    scale = comm.allreduce(max(1.0, np.abs(X).max(initial=0.0)), op=MPI.MAX)
    if hi - lo > 1e-9 * scale:
        raise ValueError(
            f"symmetry plane on {edge}: the edge is not in a plane normal to {AXES[axis]} "
            f"({AXES[axis]} spans {lo:.6g} to {hi:.6g} along it)"
        )
    along = [comm.allreduce(bool(np.all(np.isclose(np.abs(t[axis]), 1.0))), op=MPI.LAND) for t in (t2, t1)]
    if not any(along):
        raise ValueError(
            f"symmetry plane on {edge}: the plane normal to {AXES[axis]} must contain the shell's "
            "normal, i.e. be normal to the tangent t1 or t2 all along the edge"
        )
    angle = 0 if along[0] else 1
    return [facet_condition(model, sub, facets)[1] for sub in ((0, axis), (1, angle))]


def fixed_point(model, point, directions: str = "xyz") -> list:
    """Zero displacement along ``directions`` (any of x, y, z) at the node at ``point``
    (parameter coordinates); the node's existence is the caller's to check."""
    if not directions or any(c not in AXES for c in directions):
        raise ValueError(f"fix_point: directions {directions!r} must be made of x, y and z")
    bcs = []
    for c in directions:
        space = model.W.sub(0).sub(AXES.index(c))
        collapsed, _ = space.collapse()
        dofs = dolfinx.fem.locate_dofs_geometrical((space, collapsed), at_node(point))
        bcs.append(dolfinx.fem.dirichletbc(dolfinx.fem.Function(collapsed), dofs, space))
    return bcs
