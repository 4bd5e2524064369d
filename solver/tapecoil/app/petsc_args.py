"""The command line's PETSc options: split off tapecoil's own arguments and handed to PETSc."""

from __future__ import annotations

import sys

from tapecoil.core.petsc_options import is_option_value

PETSC_EPILOG = (
    "PETSc options for a solver go after tapecoil's own arguments, under the solver's prefix: "
    "coil_ (flattening and coiling), deploy_ (deployment), verify_<case>_ (the case's dashes as "
    "underscores), e.g. tapecoil coil --mesh coarse -coil_snes_monitor. They win over the "
    "configuration's petsc_options tables."
)


def split_petsc_options(argv: list[str], known: set[str]) -> tuple[list[str], list[str]]:
    """``argv`` as tapecoil's own arguments and the PETSc options among them.

    A PETSc option is a single dash and a letter (``-coil_snes_monitor``) that tapecoil does not
    know. As on PETSc's own command line, the argument after it is its value unless it is an
    option itself: a positional argument of tapecoil after a PETSc option would be taken as
    the option's value, hence PETSc options go last. Nothing after ``--`` is split off.
    """
    ours: list[str] = []
    petsc: list[str] = []
    i = 0
    while i < len(argv):
        arg = argv[i]
        if arg == "--":
            ours.extend(argv[i:])
            break
        if len(arg) > 1 and arg[0] == "-" and arg[1].isalpha() and arg.split("=", 1)[0] not in known:
            petsc.append(arg)
            if i + 1 < len(argv) and is_option_value(argv[i + 1]):
                petsc.append(argv[i + 1])
                i += 1
        else:
            ours.append(arg)
        i += 1
    return ours, petsc


def hand_to_petsc(options: list[str]):
    """Give the command line's PETSc options to PETSc; returns what takes them back out.

    Before PETSc is loaded they go to its initialisation, as its own command line would (so
    that -log_view and the like work); once it is loaded (``main`` called in a process that
    already ran solvers), into its options database, from which they are removed again when
    the command is done. Every MPI rank has the same command line and does the same.
    """
    if not options:
        return lambda: None
    if "petsc4py.PETSc" not in sys.modules:
        import petsc4py
        from mpi4py import MPI  # noqa: F401  (MPI first, as in every DOLFINx program)

        petsc4py.init([sys.argv[0], *options])
        return lambda: None
    from petsc4py import PETSc

    opts = PETSc.Options()
    before = opts.getAll()
    opts.insertString(" ".join(f'"{o}"' if any(c.isspace() for c in o) else o for o in options))
    changed = {k: before.get(k) for k, v in opts.getAll().items() if before.get(k, object()) != v}

    def take_back():
        for key, value in changed.items():
            if value is None:
                opts.delValue(key)
            else:
                opts[key] = value

    return take_back
