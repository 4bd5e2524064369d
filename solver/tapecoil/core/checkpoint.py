"""Checkpoints: everything a run needs to continue, written atomically with adios4dolfinx.

A checkpoint is a directory holding ``state.bp`` (ADIOS2: the mesh, its tags and named
functions, readable on any number of ranks), ``meta.json`` (the scalars and the history so
far) and, for a model with state on meshes it builds again, ``tables.npz`` (that state cell by
cell in the meshes' input order, :mod:`tapecoil.core.cell_state`). It is first written beside
its place as ``<name>.partial`` and then renamed onto it, so a run killed while writing keeps
its previous checkpoint.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import dolfinx
import numpy as np

from tapecoil.core import compat


def write_checkpoint(
    path: str | Path, mesh, tags: dict, functions: dict, meta: dict, comm, tables: dict | None = None
) -> None:
    """Write ``mesh`` with its ``tags`` (name -> MeshTags), ``functions`` (name -> Function on the
    mesh), ``meta`` (JSON-ready) and ``tables`` (name -> array, rank 0's are written) to the
    directory ``path`` (collective)."""
    import adios4dolfinx

    path = Path(path)
    partial = path.with_name(path.name + ".partial")
    if comm.rank == 0:
        shutil.rmtree(partial, ignore_errors=True)
        partial.mkdir(parents=True)
    comm.barrier()
    bp = partial / "state.bp"
    adios4dolfinx.write_mesh(bp, mesh)
    for name, meshtags in tags.items():
        adios4dolfinx.write_meshtags(bp, mesh, meshtags, meshtag_name=name)
    for name, function in functions.items():
        adios4dolfinx.write_function(bp, function, name=name)
    if comm.rank == 0:
        (partial / "meta.json").write_text(json.dumps(meta, indent=1, default=_json_default))
        if tables:
            np.savez(partial / "tables.npz", **tables)
        old = path.with_name(path.name + ".old")
        if path.exists():
            path.rename(old)
        partial.rename(path)
        shutil.rmtree(old, ignore_errors=True)
    comm.barrier()


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def read_meta(path: str | Path) -> dict:
    """The checkpoint's meta.json."""
    return json.loads((Path(path) / "meta.json").read_text())


def read_tables(path: str | Path) -> dict[str, np.ndarray] | None:
    """The checkpoint's tables (every rank reads them), or None when it has none."""
    file = Path(path) / "tables.npz"
    if not file.is_file():
        return None
    with np.load(file) as data:
        return {name: data[name] for name in data.files}


def is_checkpoint(path: str | Path) -> bool:
    path = Path(path)
    return (path / "meta.json").is_file() and (path / "state.bp").exists()


def read_mesh(path: str | Path, comm, tag_names: tuple[str, ...]) -> tuple:
    """The mesh of a checkpoint, distributed over ``comm`` (any rank count), and its tags by name."""
    import adios4dolfinx

    bp = Path(path) / "state.bp"
    mesh = adios4dolfinx.read_mesh(bp, comm)
    return mesh, {name: adios4dolfinx.read_meshtags(bp, mesh, meshtag_name=name) for name in tag_names}


def read_functions(path: str | Path, functions: dict) -> None:
    """Fill ``functions`` (name -> Function on the checkpoint's mesh) from the checkpoint."""
    import adios4dolfinx

    bp = Path(path) / "state.bp"
    for name, function in functions.items():
        adios4dolfinx.read_function(bp, function, name=name)
        function.x.scatter_forward()


def state_parts(state, prefix: str) -> dict:
    """Copies of the displacement and rotation parts of a shell-state Function, for writing."""
    out = {}
    for part, i in (("displacement", 0), ("rotation", 1)):
        space, dofs = compat.collapse(state.function_space.sub(i))
        f = dolfinx.fem.Function(space, name=f"{prefix}{part}")
        f.x.array[:] = state.x.array[dofs]
        out[f"{prefix}{part}"] = f
    return out


def empty_state_parts(space, prefix: str) -> dict:
    """Functions shaped like :func:`state_parts` of a state in ``space``, to read into."""
    return {
        f"{prefix}{part}": dolfinx.fem.Function(space.sub(i).collapse()[0], name=f"{prefix}{part}")
        for part, i in (("displacement", 0), ("rotation", 1))
    }


def set_state(state, parts: dict, prefix: str) -> None:
    """Put the parts read by :func:`read_functions` back into the shell-state Function."""
    for part, i in (("displacement", 0), ("rotation", 1)):
        _, dofs = compat.collapse(state.function_space.sub(i))
        state.x.array[dofs] = parts[f"{prefix}{part}"].x.array
    state.x.scatter_forward()
