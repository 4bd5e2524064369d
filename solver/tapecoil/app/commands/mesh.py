"""``tapecoil mesh``: the tape's strip mesh written for gmsh and ParaView."""

from __future__ import annotations

import argparse

from tapecoil.app.commands.common import echo, with_mesh
from tapecoil.config import ConfigError, load_config


def cmd_mesh(args: argparse.Namespace) -> int:
    """The configured tape's strip mesh as gmsh and XDMF files, for gmsh and ParaView."""
    from pathlib import Path

    config = with_mesh(load_config(args.config), args.preset)  # refused before MPI starts
    from mpi4py import MPI

    from tapecoil.core.collective import raise_everywhere
    from tapecoil.geometry.meshes import MeshResolution, write_strip_mesh
    from tapecoil.geometry.surfaces import StripGeometry

    comm, directory = MPI.COMM_WORLD, Path(args.out)
    error = None
    if comm.rank == 0:
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            error = ConfigError(f"--out {directory}: cannot create the directory ({exc.strerror or exc})")
    raise_everywhere(comm, error)
    tp, preset = config.tape, config.mesh.preset
    res = MeshResolution.from_config(config.mesh, tp.L)
    files = write_strip_mesh(comm, StripGeometry.from_config(config), res, directory, f"strip-{preset}")
    first, last = res.element_lengths(tp.L)
    along = f"{first * 1e3:.4g} mm" if res.grading == 1.0 else f"{first * 1e3:.4g} to {last * 1e3:.4g} mm"
    echo(
        f"strip mesh of the tape (L = {tp.L:g} m, arc width {tp.b * 1e3:.4g} mm), preset {preset}: "
        f"{res.along} x {res.across} quadrilaterals\n"
        f"  {files.nodes} nodes, {files.cells} cells; element size {along} along the tape, "
        f"{tp.b / res.across * 1e3:.4g} mm across"
    )
    for path, what in (
        (files.msh, "gmsh, parameter coordinates (xi_1, xi_2): the solver's mesh"),
        (files.xdmf, "XDMF, the same: mesh 'strip', tags 'facets' and 'cells'"),
        (files.surface_msh, "gmsh, the 3D mid-surface"),
        (files.surface_xdmf, "XDMF, the 3D mid-surface: mesh 'surface', tags 'facets' and 'cells'"),
    ):
        echo(f"  {path!s:<{max(len(str(files.surface_xdmf)), 24)}}  {what}")
    return 0
