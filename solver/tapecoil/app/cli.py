"""Command line: ``tapecoil theory [config.toml] [--json]`` and the simulation commands.

The parser and the dispatch to the commands (:mod:`tapecoil.app.commands`), with the PETSc
options split off the command line (:mod:`tapecoil.app.petsc_args`). Configuration errors are
reported as one line naming the key and the allowed range, with exit status 2, before anything
is computed. The commands that coil (``coil``, ``run``, the coil and run sweeps) also warn,
before computing, of what is likely to keep the coiling from its goal
(:meth:`tapecoil.config.Config.coiling_warnings`): a ConfigWarning, shown as one line
``tapecoil: warning: ...`` on stderr, and the same in the run's run.log. Output is printed by
MPI rank 0 only.
"""

from __future__ import annotations

import argparse
import sys
import warnings

from tapecoil import __version__
from tapecoil.app.commands.fold import cmd_fold
from tapecoil.app.commands.info import cmd_config, cmd_theory
from tapecoil.app.commands.mesh import cmd_mesh
from tapecoil.app.commands.runs import cmd_coil, cmd_deploy, cmd_payout, cmd_report, cmd_run, cmd_sweep
from tapecoil.app.commands.verify import cmd_verify
from tapecoil.app.petsc_args import PETSC_EPILOG, hand_to_petsc, split_petsc_options
from tapecoil.config import ConfigError, ConfigWarning


def _format_warning(message, category, filename, lineno, line=None) -> str:
    """Nothing for a ConfigWarning (printed already, see warn_before_coiling); others as Python does."""
    if issubclass(category, ConfigWarning):
        return ""
    return _PYTHON_FORMAT_WARNING(message, category, filename, lineno, line)


_PYTHON_FORMAT_WARNING = warnings.formatwarning  # Python's own, whatever main finds set


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tapecoil", description="Coiling and deployment of tape springs (FEniCSx)."
    )
    parser.add_argument("--version", action="version", version=f"tapecoil {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("theory", help="analytic predictions for a configuration")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(func=cmd_theory)

    from tapecoil.verification import CASES

    p = sub.add_parser(
        "verify", help="run the shell's and the beam's verification cases against their references"
    )
    p.add_argument("case", nargs="?", default="all", choices=(*CASES, "all"))
    p.add_argument("config", nargs="?", help="TOML configuration (the tape cases use its tape)")
    p.add_argument(
        "--mesh",
        choices=("coarse", "default", "fine"),
        help="mesh preset (default: each case's coarsest that passes: default for tape-fold, else coarse)",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument(
        "--out",
        help="directory of the curves the path cases write, CSV and PNG: roof-*, tape-moment-rotation "
        "(default: <output.directory>/verify)",
    )
    p.set_defaults(func=cmd_verify)

    p = sub.add_parser(
        "fold",
        help="a tape spring's moment-rotation curve in both senses: stable and unstable branches, "
        "peak moments, snaps, steady fold moments (arc length)",
    )
    p.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
    p.add_argument(
        "--mesh",
        choices=("coarse", "default", "fine"),
        default="coarse",
        help="mesh preset (default: coarse)",
    )
    p.add_argument("--out", help="results directory (default: <output.directory>/fold)")
    p.add_argument("--angle", type=float, help="end rotation to fold to [rad], in (0, pi] (default: 2)")
    p.add_argument(
        "--length", type=float, help="length of the tape bent [m] (default: the tape's, at most 16 R)"
    )
    p.add_argument("--sense", choices=("opposite", "equal", "both"), default="both", help="bending sense")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=cmd_fold)

    p = sub.add_parser("coil", help="coil the tape onto the hub to the stowed state (quasi-static)")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
    p.add_argument("--mesh", choices=("coarse", "default", "fine"), help="mesh preset (overrides the file)")
    _model_option(p)
    p.add_argument("--out", help="results directory (default: <output.directory>/coil)")
    p.add_argument(
        "--resume",
        nargs="?",
        const="",
        metavar="CHECKPOINT",
        help="continue from a checkpoint (default: the results directory's stowed/), as if never stopped",
    )
    _common_run_options(p)
    p.set_defaults(func=cmd_coil)

    _from_stowed_command(
        sub, "deploy", "deploy from a stowed checkpoint (implicit dynamics)", "deployed", cmd_deploy
    )
    _from_stowed_command(
        sub,
        "payout",
        "pay the tape out of a stowed checkpoint with a driven hub, the pull held (quasi-static)",
        "paid_out",
        cmd_payout,
    )

    p = sub.add_parser("run", help="the whole pipeline: coil, stow, deploy")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
    p.add_argument("--mesh", choices=("coarse", "default", "fine"), help="mesh preset (overrides the file)")
    _model_option(p)
    p.add_argument("--out", help="results directory (default: <output.directory>/run)")
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue a stopped run from the results directory's checkpoints",
    )
    _common_run_options(p)
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("sweep", help="a parameter study, cases spread over MPI sub-communicators")
    p.add_argument("sweep", help="sweep file: a configuration with a [sweep] table (see tapecoil.app.sweep)")
    p.add_argument("--out", help="results directory (default: <output.directory>/sweep-<name>)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("report", help="(re)make the pictures and report.html of a results directory")
    p.add_argument("directory", help="results directory of tapecoil run, coil or deploy")
    p.set_defaults(func=cmd_report)

    p = sub.add_parser("mesh", help="write the tape's strip mesh (gmsh .msh and XDMF) for gmsh and ParaView")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
    p.add_argument("--preset", choices=("coarse", "default", "fine"), help="mesh preset (overrides the file)")
    p.add_argument("--out", default="meshes", help="directory of the files (default: meshes/ here)")
    p.set_defaults(func=cmd_mesh)

    p = sub.add_parser("config", help="print a configuration as TOML (the defaults if none is given)")
    p.add_argument("config", nargs="?", help="TOML configuration to check and print")
    p.set_defaults(func=cmd_config)
    return parser


def _model_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--model",
        choices=("shell", "hybrid"),
        help="the tape's model, model.kind (overrides the file): the full shell, or the "
        "shell-beam hybrid (it coils and deploys; its stowed state is the full shell's)",
    )


def _common_run_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print the JSON summary (summary.json)")
    p.add_argument("--no-report", action="store_true", help="skip the pictures and report.html")


def _from_stowed_command(sub, name: str, help: str, checkpoint: str, func) -> None:
    """A command that starts from a stowed checkpoint and resumes from its own ``checkpoint``/."""
    p = sub.add_parser(name, help=help)
    p.add_argument("stowed", help="stowed checkpoint directory (a coiling run's stowed/)")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the one beside the checkpoint)")
    p.add_argument("--out", help=f"results directory (default: <output.directory>/{name})")
    p.add_argument(
        "--resume", action="store_true", help=f"continue from the results directory's {checkpoint}/"
    )
    _common_run_options(p)
    p.set_defaults(func=func)


def _known_options(parser: argparse.ArgumentParser) -> set[str]:
    """The option strings of ``parser`` and of its commands' parsers."""
    known = set(parser._option_string_actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                known |= _known_options(sub)
    return known


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    parser.epilog = PETSC_EPILOG
    argv = sys.argv[1:] if argv is None else list(argv)
    ours, petsc = split_petsc_options(argv, _known_options(parser))
    args = parser.parse_args(ours)
    take_back = hand_to_petsc(petsc)
    # a ConfigWarning is printed as one line where it is raised; Python's display would repeat it
    shown_as, warnings.formatwarning = warnings.formatwarning, _format_warning
    try:
        return args.func(args)
    except ConfigError as exc:
        print(f"tapecoil: configuration error: {exc}", file=sys.stderr)
        return 2
    finally:
        warnings.formatwarning = shown_as
        take_back()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
