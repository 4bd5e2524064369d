"""What the commands share: printing on MPI rank 0 only, and the command line's mesh preset."""

from __future__ import annotations

import os
import sys


def rank() -> int:
    """This process's MPI rank, without starting MPI for the commands that need none.

    Once a command has loaded MPI, MPI answers; before that (``theory``, ``config``) the launcher's
    environment does, so that ``mpirun -n 2 tapecoil theory`` still prints one table.
    """
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None:
        return mpi.COMM_WORLD.rank
    for name in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"):
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return 0


def echo(text: str = "") -> None:
    if rank() == 0:
        print(text, flush=True)


def with_model(config, kind: str | None):
    """``config`` with model.kind set to ``kind`` (a command line's --model), checked again."""
    import dataclasses

    if kind is None:
        return config
    config = dataclasses.replace(config, model=dataclasses.replace(config.model, kind=kind))
    config.check()
    return config


def with_mesh(config, preset: str | None):
    import dataclasses

    if preset is None:
        return config
    return dataclasses.replace(config, mesh=dataclasses.replace(config.mesh, preset=preset))
