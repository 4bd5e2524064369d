"""Warnings given before a run computes: what is likely to keep a coiling from its goal.

The configuration refuses what cannot be computed (:meth:`tapecoil.config.Config.check`); what
can be computed but will likely not coil (a pull below the tension the hub needs,
:meth:`tapecoil.config.Config.coiling_warnings`) is warned of here, by the commands and sweeps
that start a coiling, before anything is computed.
"""

from __future__ import annotations

import sys
import warnings

from tapecoil.config import ConfigWarning


def warn_before_coiling(
    config, directory=None, comm=None, prefix: str = "", console: bool = True
) -> list[str]:
    """Warn of what is likely to keep a coiling from its goal, before anything is computed.

    Each of ``config.coiling_warnings()``, with ``prefix`` before it (a sweep names its case):
    when ``console``, as a :class:`ConfigWarning` (for callers that catch or record warnings)
    and as the line ``tapecoil: warning: ...`` on stderr; when a directory is given, into its
    run.log (created; the run appends to it). By rank 0 of ``comm`` only (no ``comm``: this
    process). Returns the messages (on every rank).

    The line is printed, not left to Python's display of the warning: once FFCx is imported
    (by DOLFINx, before any run) it sends warnings to the logging module, where nobody shows them.
    """
    messages = [prefix + m for m in config.coiling_warnings()]
    if not messages or (comm is not None and comm.rank != 0):
        return messages
    if console:
        for message in messages:
            warnings.warn(message, ConfigWarning, stacklevel=2)
            print(f"tapecoil: warning: {message}", file=sys.stderr, flush=True)
    if directory is not None:
        from pathlib import Path

        from mpi4py import MPI

        from tapecoil.app import results

        Path(directory).mkdir(parents=True, exist_ok=True)
        handler = results.start_log(directory, MPI.COMM_SELF)  # this rank is rank 0 of comm
        try:
            for message in messages:
                results.LOG.warning("configuration: %s", message)
        finally:
            results.stop_log(handler)
    return messages
