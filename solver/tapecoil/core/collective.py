"""Errors of work done on one rank, raised on every rank.

Work that only one rank does (writing a file, meshing with gmsh) can fail there alone. If that
rank raised and the others walked on, they would wait in their next collective operation for
ever. So the rank that did the work broadcasts its outcome, and every rank raises the same
exception (same type and message) at the same point.
"""

from __future__ import annotations

import pickle


def _transportable(error: BaseException) -> BaseException:
    """``error`` if it survives pickling (what the broadcast does), else a RuntimeError naming it."""
    try:
        copy = pickle.loads(pickle.dumps(error))
    except Exception:
        return RuntimeError(f"{type(error).__name__}: {error}")
    return copy if isinstance(copy, BaseException) else RuntimeError(f"{type(error).__name__}: {error}")


def raise_everywhere(comm, error: BaseException | None, root: int = 0) -> None:
    """Raise ``error`` (the outcome of the work on ``root``) on every rank of ``comm`` (collective).

    ``error`` is what ``root`` caught, or None when its work succeeded; the other ranks' value is
    ignored. ``root`` re-raises its own exception (with its traceback), the others a copy of it.
    With ``comm`` None (serial use) ``error`` is raised as it is.
    """
    if comm is None:
        if error is not None:
            raise error
        return
    received = comm.bcast(None if error is None or comm.rank != root else _transportable(error), root=root)
    if received is None:
        return
    if comm.rank == root:
        raise error
    raise received
