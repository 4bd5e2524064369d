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
import numpy as np

from . import compat
from .shell import NaghdiShell


class NonFiniteStateError(RuntimeError):
    """A state with NaN or infinite values was about to be written."""


class ShellWriter:
    """VTX time series of a shell's 3D shape and fields: ``write(t)`` after each step."""

    def __init__(self, model: NaghdiShell, path: str | Path):
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
            self.fields.append((f, dolfinx.fem.Expression(expr, points)))
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        self.writer = dolfinx.io.VTXWriter(mesh.comm, str(path), [f for f, _ in self.fields], engine="BP4")

    def write(self, t: float) -> None:
        bad = 0
        for f, expr in self.fields:
            f.interpolate(expr)
            bad += int(not np.all(np.isfinite(f.x.array)))
        if self.model.mesh.comm.allreduce(bad):
            raise NonFiniteStateError(f"non-finite values in the state at t = {t:g}; not written")
        self.writer.write(t)

    def close(self) -> None:
        self.writer.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def write_csv(path: str | Path, rows: list[dict], comm=None) -> None:
    """A history as CSV (rank 0 writes); refuses rows with non-finite numbers."""
    if comm is not None and comm.rank != 0:
        return
    for row in rows:
        for key, value in row.items():
            if isinstance(value, float) and not np.isfinite(value):
                raise NonFiniteStateError(f"non-finite {key} in a history row; not written")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else [])
        writer.writeheader()
        writer.writerows(rows)
