"""PETSc options of a solver: tapecoil's defaults, a caller-named prefix, and the database.

Each solver's options go into PETSc's global options database under the solver's prefix only
while PETSc reads them, so that the command line wins and nothing set for one solver reaches
the next. The command line is the process's own (``sys.argv``), whoever started it: the
``tapecoil`` command or a user's script (``python3 my_script.py -shell_snes_monitor``); PETSc
itself reads it only when petsc4py is initialised with it, which importing DOLFINx does not do.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Sequence
from contextlib import contextmanager

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


def is_option_value(arg: str) -> bool:
    """Whether a command-line argument after a PETSc option is its value (as PETSc reads it):
    anything but another option, a negative number being a value."""
    if not arg.startswith("-"):
        return True
    try:
        float(arg)
    except ValueError:
        return False
    return True


def command_line_options(prefix: str, argv: Sequence[str] | None = None) -> dict[str, str]:
    """The PETSc options of a command line named under ``prefix``, names without it.

    ``-shell_snes_rtol 1e-3 -shell_snes_monitor`` under ``shell_`` gives
    {"snes_rtol": "1e-3", "snes_monitor": ""}: as on PETSc's own command line, the argument
    after an option is its value unless it is an option itself. Nothing after ``--`` is read.
    ``argv``: the arguments, by default the process's own (``sys.argv[1:]``).
    """
    argv = sys.argv[1:] if argv is None else list(argv)
    found: dict[str, str] = {}
    i = 0
    while i < len(argv):
        arg = argv[i]
        if arg == "--":
            break
        if arg.startswith(f"-{prefix}") and len(arg) > len(prefix) + 1:
            value = ""
            if i + 1 < len(argv) and is_option_value(argv[i + 1]):
                value = argv[i + 1]
                i += 1
            found[arg[len(prefix) + 1 :]] = value
        i += 1
    return found


@contextmanager
def options_in_database(prefix: str, options: dict):
    """``options`` (names without ``prefix``) in PETSc's global database while PETSc reads them,
    with the process's command line's options under ``prefix`` over them.

    A key the database already holds (options a caller put there, or the ``tapecoil`` command's
    hand-over of its command line) is left alone, so it wins; the keys inserted here are deleted
    afterwards, so that none reaches the next solver with the same prefix. Solves run inside
    this too: PETSc reads some options only when it sets up the factorisation at the first solve
    (MUMPS' ``mat_mumps_icntl_*``), long after setFromOptions. The database is per process;
    every rank has the same command line and inserts the same keys.
    """
    # imported here: the command line's reading above must not load PETSc, which the
    # tapecoil command initialises with its options only once it has split them off
    from petsc4py import PETSc

    opts = PETSc.Options()
    inserted = []
    for key, value in {**options, **command_line_options(prefix)}.items():
        name = prefix + key
        if not opts.hasName(name):
            opts[name] = value
            inserted.append(name)
    try:
        yield
    finally:
        for name in inserted:
            opts.delValue(name)
