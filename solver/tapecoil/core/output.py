"""ParaView output of shell states (VTX / ADIOS2) and CSV histories.

The DOLFINx mesh lives in parameter coordinates (xi_1, xi_2, 0). Every snapshot carries the
vector field ``offset`` = phi0(xi) + u - (xi_1, xi_2, 0): in ParaView, *Warp By Vector* with
``offset`` (scale 1) turns the flat parameter mesh into the deformed 3D shell, and with
``u = 0`` into the reference surface; the same surface gmsh built. Also written: the
displacement ``u``, the director ``d``, and the longitudinal and transverse curvatures.
No non-finite value is ever written: a snapshot with one raises instead.
"""

from __future__ import annotations

import csv
from pathlib import Path

import dolfinx
import dolfinx.plot
import numpy as np

from tapecoil.core import compat
from tapecoil.core.collective import raise_everywhere
from tapecoil.core.expression import expression_at


class NonFiniteStateError(RuntimeError):
    """A state with NaN or infinite values was about to be written."""


class ShellWriter:
    """VTX time series of a shell's 3D shape and fields: ``write(t)`` after each step.

    ``model`` is a shell model: its mesh, state ``q``, ``display_offset`` and ``curvatures()``.

    With ``snapshots`` (a directory) every write also gathers the deformed surface and its
    longitudinal curvature on rank 0 into ``<phase>_<n>.npz`` there (points and values; the
    cells and the points' reference coordinates ``xi`` once, in ``<phase>_cells.npz``), from
    which pictures are made without ParaView and whatever the number of ranks. ``first_index``
    numbers the first snapshot (a resumed run goes on counting).
    """

    def __init__(
        self,
        model,
        path: str | Path,
        snapshots: str | Path | None = None,
        phase: str = "shell",
        first_index: int = 0,
    ):
        import basix.ufl

        self.model = model
        mesh = model.mesh
        cell = mesh.basix_cell()
        V3 = dolfinx.fem.functionspace(mesh, basix.ufl.element("Lagrange", cell, model.degree, shape=(3,)))
        V1 = dolfinx.fem.functionspace(mesh, basix.ufl.element("Lagrange", cell, model.degree))
        points = compat.interpolation_points(V3)
        kx, ky = model.curvatures()
        self.fields = []
        for name, space, expr in (
            ("offset", V3, model.display_offset),
            ("u", V3, model.u),
            ("d", V3, model.d),
            ("kappa_long", V1, kx),
            ("kappa_trans", V1, ky),
        ):
            f = dolfinx.fem.Function(space, name=name)
            self.fields.append((f, expression_at(expr, points)))
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        self.writer = dolfinx.io.VTXWriter(mesh.comm, str(path), [f for f, _ in self.fields], engine="BP4")
        self.snapshots = None if snapshots is None else Path(snapshots)
        self.phase, self.index = phase, first_index
        if self.snapshots is not None:
            cells, types, x = dolfinx.plot.vtk_mesh(V3)
            self._local_points = x
            pieces = mesh.comm.gather((cells, types, x.shape[0], x[:, :2].copy()), root=0)
            if mesh.comm.rank == 0:
                self.snapshots.mkdir(parents=True, exist_ok=True)
                merged, offset = [], 0
                for piece_cells, _, n_points, _ in pieces:
                    if piece_cells.size:  # VTK layout: node count, then the nodes, per cell
                        c = piece_cells.reshape(-1, piece_cells[0] + 1).copy()
                        c[:, 1:] += offset
                        merged.append(c.ravel())
                    offset += n_points
                np.savez_compressed(
                    self.snapshots / f"{phase}_cells.npz",
                    cells=np.concatenate(merged),
                    types=np.concatenate([p[1] for p in pieces]),
                    # the points' reference (material) coordinates, in the order of every snapshot
                    xi=np.vstack([p[3] for p in pieces]),
                )

    def write(self, t: float) -> None:
        bad = 0
        for f, expr in self.fields:
            f.interpolate(expr)
            bad += int(not np.all(np.isfinite(f.x.array)))
        if self.model.mesh.comm.allreduce(bad):
            raise NonFiniteStateError(f"non-finite values in the state at t = {t:g}; not written")
        self.writer.write(t)
        if self.snapshots is not None:
            self._snapshot(t)

    def _snapshot(self, t: float) -> None:
        """Gather the deformed surface on rank 0 and save it (collective)."""
        offset, kappa = self.fields[0][0], self.fields[3][0]
        points = self._local_points + offset.x.array.reshape(-1, 3)
        comm = self.model.mesh.comm
        pieces = comm.gather((points.astype(np.float32), kappa.x.array.astype(np.float32)), root=0)
        if comm.rank == 0:
            np.savez_compressed(
                self.snapshots / f"{self.phase}_{self.index:05d}.npz",
                t=t,
                points=np.vstack([p[0] for p in pieces]),
                kappa_long=np.concatenate([p[1] for p in pieces]),
            )
        self.index += 1

    def close(self) -> None:
        self.writer.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def write_csv(path: str | Path, rows: list[dict], comm=None) -> None:
    """A history as CSV (rank 0 writes; collective over ``comm``); refuses non-finite numbers.

    Whatever stops rank 0 (a non-finite value, a path it cannot write) is raised on every rank,
    so that no rank waits in the next collective operation for one that has given up.
    """
    error = None
    if comm is None or comm.rank == 0:
        try:
            _write_csv(Path(path), rows)
        except Exception as exc:
            error = exc
    raise_everywhere(comm, error)


def _write_csv(path: Path, rows: list[dict]) -> None:
    for row in rows:
        for key, value in row.items():
            if isinstance(value, float) and not np.isfinite(value):
                raise NonFiniteStateError(f"non-finite {key} in a history row; not written")
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        # every row's columns, in order of appearance: a history continued from an older
        # checkpoint may lack columns of the rows after it (left empty there)
        fields = list(dict.fromkeys(key for row in rows for key in row))
        writer = csv.DictWriter(f, fieldnames=fields, restval="")
        writer.writeheader()
        writer.writerows(rows)
