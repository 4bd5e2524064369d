"""The DOLFINx 0.9 / 0.10 / 0.11 differences tapecoil meets, hidden behind one small API.

Everything else in the package calls these functions instead of the moved or renamed
DOLFINx ones, so that supporting a new release means touching only this module.
"""

from __future__ import annotations

import dolfinx
import dolfinx.fem.petsc
import dolfinx.la
import numpy as np

DOLFINX_VERSION: tuple[int, int] = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])  # type: ignore[assignment]
"""(major, minor) of the DOLFINx in use."""

if DOLFINX_VERSION < (0, 9):  # pragma: no cover - refused before anything runs
    raise ImportError(f"tapecoil needs DOLFINx >= 0.9, found {dolfinx.__version__}")

if DOLFINX_VERSION >= (0, 10):  # pragma: no cover - exercised on conda / Debian sid
    from dolfinx.io import gmsh as _gmshio
else:
    from dolfinx.io import gmshio as _gmshio


def model_to_mesh(model, comm, rank: int, gdim: int):
    """A gmsh model (meshed on ``rank``) as a distributed DOLFINx mesh with its tags.

    Returns ``(mesh, cell_tags, facet_tags)`` on every version: 0.9 returns that tuple, 0.10+
    a ``MeshData`` named tuple (whose missing tags are None in 0.11).
    """
    data = _gmshio.model_to_mesh(model, comm, rank, gdim=gdim)
    if isinstance(data, tuple) and not hasattr(data, "mesh"):
        return data
    return data.mesh, data.cell_tags, data.facet_tags


def interpolation_points(V) -> np.ndarray:
    """Reference interpolation points of a function space's element (method in 0.9, property after)."""
    points = V.element.interpolation_points
    return points() if callable(points) else points


def create_vector(V):
    """A ghosted PETSc vector laid out like the function space V (0.9 takes a form, 0.10+ a space)."""
    if DOLFINX_VERSION >= (0, 10):  # pragma: no cover
        return dolfinx.fem.petsc.create_vector(V)
    return dolfinx.la.create_petsc_vector(V.dofmap.index_map, V.dofmap.index_map_bs)


def assemble_matrix(A, a, bcs, diagonal: float = 1.0):
    """Assemble the bilinear form ``a`` into A with Dirichlet rows set to ``diagonal``.

    Positional on purpose: the keyword is ``diagonal`` in 0.9 and ``diag`` in 0.11.
    """
    return dolfinx.fem.petsc.assemble_matrix(A, a, bcs, diagonal)


def create_mesh(comm, cells, x, element, partitioner=None):
    """``dolfinx.mesh.create_mesh`` by keyword: 0.10 swapped the positions of x and the element."""
    return dolfinx.mesh.create_mesh(comm, cells=cells, x=x, e=element, partitioner=partitioner)
