"""PETSc options of a solver: tapecoil's defaults, a caller-named prefix, and the database.

Each solver's options go into PETSc's global options database under the solver's prefix only
while PETSc reads them, so that the command line (already in the database) wins and nothing
set for one solver reaches the next.
"""

from __future__ import annotations

import re
from contextlib import contextmanager

from petsc4py import PETSc

DEFAULT_PETSC_OPTIONS = {
    "snes_type": "newtonls",
    # full Newton steps: with large rotation increments the backtracking line search creeps
    # (measured on the roll-up cantilever); load-step cut-back handles divergence instead
    "snes_linesearch_type": "basic",
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}

_PREFIX = re.compile(r"[A-Za-z][A-Za-z0-9_]*_")


def check_prefix(prefix) -> None:
    """Refuse an options prefix PETSc would misread (letters, digits, underscores; ends in _)."""
    if not isinstance(prefix, str) or not _PREFIX.fullmatch(prefix):
        raise ValueError(
            f"PETSc options prefix {prefix!r}: letters, digits and underscores, starting with a "
            "letter and ending in an underscore (e.g. 'coil_')"
        )


@contextmanager
def options_in_database(prefix: str, options: dict):
    """``options`` (names without ``prefix``) in PETSc's global database while PETSc reads them.

    A key the database already holds (the user's command line) is left alone, so it wins;
    the keys inserted here are deleted afterwards, so that none reaches the next solver
    with the same prefix. Solves run inside this too: PETSc reads some options only when it
    sets up the factorisation at the first solve (MUMPS' ``mat_mumps_icntl_*``), long after
    setFromOptions. The database is per process; every rank inserts the same keys.
    """
    opts = PETSc.Options()
    inserted = []
    for key, value in options.items():
        name = prefix + key
        if not opts.hasName(name):
            opts[name] = value
            inserted.append(name)
    try:
        yield
    finally:
        for name in inserted:
            opts.delValue(name)
