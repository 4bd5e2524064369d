"""Command line: ``tapecoil theory [config.toml] [--json]`` and the simulation commands.

Configuration errors are reported as one line naming the key and the allowed range, with
exit status 2, before anything is computed. The commands that coil (``coil``, ``run``, the coil
and run sweeps) also warn, before computing, of what is likely to keep the coiling from its goal
(:meth:`tapecoil.config.Config.coiling_warnings`): a ConfigWarning, shown as one line
``tapecoil: warning: ...`` on stderr, and the same in the run's run.log. Output is printed by
MPI rank 0 only.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import warnings

from tapecoil import __version__
from tapecoil.app.checks import warn_before_coiling
from tapecoil.config import ConfigError, ConfigWarning, load_config


def _rank() -> int:
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


def _echo(text: str = "") -> None:
    if _rank() == 0:
        print(text, flush=True)


def _format_warning(message, category, filename, lineno, line=None) -> str:
    """Nothing for a ConfigWarning (printed already, see warn_before_coiling); others as Python does."""
    if issubclass(category, ConfigWarning):
        return ""
    return _PYTHON_FORMAT_WARNING(message, category, filename, lineno, line)


_PYTHON_FORMAT_WARNING = warnings.formatwarning  # Python's own, whatever main finds set


# Display units for the table: (SI unit, key) -> (factor, shown unit)
_DISPLAY = {"m": (1e3, "mm"), "Pa": (1e-6, "MPa"), "N m": (1e3, "N mm"), "m^4": (1e12, "mm^4")}


def _display(value: float, unit: str) -> tuple[str, str]:
    factor, shown = _DISPLAY.get(unit, (1.0, unit))
    v = value * factor
    text = f"{v:.4g}" if abs(v) < 1e5 else f"{v:.4e}"
    return text, shown


def cmd_theory(args: argparse.Namespace) -> int:
    from tapecoil.theory import predictions

    config = load_config(args.config)
    preds = predictions(config)
    if args.json:
        payload = {
            "config": args.config or "defaults (benchmark tape)",
            "predictions": {
                p.key: {"label": p.label, "value": p.value, "unit": p.unit, "source": p.source} for p in preds
            },
        }
        _echo(json.dumps(payload, indent=2))
        return 0
    tp = config.tape
    _echo(f"tapecoil {__version__}: analytic predictions ({args.config or 'benchmark tape, defaults'})")
    _echo(
        f"tape R = {tp.R * 1e3:g} mm, alpha = {math.degrees(tp.alpha):.4g} deg, h = {tp.h * 1e3:g} mm, "
        f"L = {tp.L:g} m, E = {tp.E / 1e9:g} GPa, nu = {tp.nu:g}, rho_l = {tp.rho_l:g} kg/m; "
        f"hub r = {config.hub.radius * 1e3:g} mm; hub rotation {config.coiling.hub_angle:g} rad"
    )
    rows = [(p.label, *_display(p.value, p.unit), p.source) for p in preds]
    w0 = max(len(r[0]) for r in rows)
    w1 = max(len(r[1]) for r in rows)
    w2 = max(len(r[2]) for r in rows)
    _echo()
    for label, value, unit, source in rows:
        _echo(f"  {label:<{w0}}  {value:>{w1}} {unit:<{w2}}  {source}")
    return 0


def cmd_verify(args: argparse.Namespace) -> int:
    import time

    config = load_config(args.config)
    from tapecoil.verification import CASES
    from tapecoil.verification.cases import run_case

    names = CASES if args.case == "all" else (args.case,)
    results = []
    for name in names:
        t0 = time.perf_counter()
        result = run_case(name, config, args.mesh)
        result.info["case_wall_time"] = time.perf_counter() - t0
        results.append(result)
        if not args.json:
            mesh, wall = result.info.get("mesh", ""), result.info["case_wall_time"]
            _echo(f"{name} ({result.info['preset']} mesh, {mesh}, {wall:.1f} s)")
            for c in result.checks:
                err = f"{c.error:.2e}" + ("" if c.absolute else " rel")
                _echo(
                    f"  {c.name:<40} computed {c.computed:<12.6g} reference {c.reference:<10.6g} "
                    f"error {err:<13} tol {c.tolerance:g}  {'PASS' if c.passed else 'FAIL'}"
                )
    if args.json:
        payload = [
            {
                "case": r.case,
                "passed": r.passed,
                "checks": [
                    {
                        "name": c.name,
                        "computed": c.computed,
                        "reference": c.reference,
                        "error": c.error,
                        "tolerance": c.tolerance,
                        "absolute": c.absolute,
                        "passed": c.passed,
                    }
                    for c in r.checks
                ],
                "info": r.info,
            }
            for r in results
        ]
        _echo(json.dumps(payload, indent=2, default=float))
    return 0 if all(r.passed for r in results) else 1


def _with_mesh(config, preset: str | None):
    import dataclasses

    if preset is None:
        return config
    return dataclasses.replace(config, mesh=dataclasses.replace(config.mesh, preset=preset))


def _entries(measures: dict):
    """(name, computed, reference, error) of the measures that have a reference."""
    for name, value in measures.items():
        if isinstance(value, dict) and "computed" in value and "error" in value:
            yield name, value["computed"], value["reference"], value["error"]


def _print_phase(name: str, phase: dict, directory) -> None:
    run = phase["run"]
    if name == "coiling":
        state = "stowed" if phase["completed"] else f"STOPPED: {phase['message']}"
        where = f"coiling to {phase['hub_angle']:.4g} of {phase['target_hub_angle']:g} rad"
    else:
        state = "deployed" if phase["completed"] else f"STOPPED: {phase['message']}"
        where = f"deployment to lambda = {phase['lambda']:.3f} at t = {phase['time']:.4g} s"
    _echo(
        f"{where}: {state}\n"
        f"  mesh {run['mesh']} ({run['dofs']} dofs) on {run['ranks']} rank(s): {run['steps']} steps, "
        f"{run['newton_iterations']} Newton iterations, {run['wall_time']:.1f} s; results in {directory}"
    )
    for name_, computed, reference, error in _entries(phase["measures"]):
        if computed is None:
            _echo(f"  {name_:<26} not reached; reference {reference:.5g}")
        else:
            _echo(f"  {name_:<26} computed {computed:<12.5g} reference {reference:<12.5g} error {error:.2%}")
    if name == "deployment":
        e = phase["measures"]["energy"]
        _echo(
            f"  energy: stowed {e['stowed']:.4g} J, numerically dissipated at most "
            f"{e['largest_dissipated_fraction']:.2%}, largest growth {e['largest_growth_fraction']:.2%}"
        )


def _finish(args: argparse.Namespace, summary: dict, directory) -> int:
    """Print the summary (JSON or a table) and return the exit status."""
    from tapecoil.app.pipeline import exit_status

    if args.json:
        _echo(json.dumps(summary, indent=2))
    else:
        for name in ("coiling", "deployment"):
            if name in summary:
                _print_phase(name, summary[name], directory)
        if summary["interrupted"]:
            _echo(f"interrupted ({summary['interrupted']}): continue with --resume")
    return exit_status(summary)


def _resume_path(value, directory, name):
    """--resume [CHECKPOINT]: the checkpoint given, or the results directory's own."""
    from pathlib import Path

    from tapecoil.core.checkpoint import is_checkpoint

    if value is None:
        return None
    path = Path(value) if value else Path(directory) / name
    if not is_checkpoint(path):
        raise ConfigError(f"--resume: {path} is not a checkpoint (no meta.json and state.bp in it)")
    return path


def cmd_coil(args: argparse.Namespace) -> int:
    from tapecoil.app.pipeline import run

    config = _with_mesh(load_config(args.config), args.mesh)
    directory = args.out or f"{config.output.directory}/coil"
    checkpoint = _resume_path(args.resume, directory, "stowed")
    from mpi4py import MPI

    warn_before_coiling(config, directory, MPI.COMM_WORLD)
    summary = run(
        config,
        directory,
        phases=("coiling",),
        coiling_checkpoint=checkpoint,
        progress=not args.json,
        report=False if args.no_report else None,
        command="coil",
    )
    return _finish(args, summary, directory)


def _stowed_config(args: argparse.Namespace):
    """The configuration for a deployment: the file given, else the one beside the checkpoint."""
    from pathlib import Path

    from tapecoil.core.checkpoint import is_checkpoint

    stowed = Path(args.stowed)
    if not is_checkpoint(stowed):
        raise ConfigError(f"{stowed} is not a stowed checkpoint (no meta.json and state.bp in it)")
    beside = stowed.parent / "config.toml"
    return load_config(args.config or (beside if beside.is_file() else None))


def cmd_deploy(args: argparse.Namespace) -> int:
    from tapecoil.app.pipeline import run

    config = _stowed_config(args)
    directory = args.out or f"{config.output.directory}/deploy"
    if args.resume:
        _resume_path("", directory, "deployed")
    summary = run(
        config,
        directory,
        phases=("deployment",),
        resume=args.resume,
        stowed=args.stowed,
        progress=not args.json,
        report=False if args.no_report else None,
        command="deploy",
    )
    return _finish(args, summary, directory)


def cmd_run(args: argparse.Namespace) -> int:
    """Coil, stow and deploy; with --resume, go on from the directory's checkpoints."""
    from tapecoil.app.pipeline import run

    config = _with_mesh(load_config(args.config), args.mesh)
    directory = args.out or f"{config.output.directory}/run"
    if args.resume:
        _resume_path("", directory, "stowed")
    from mpi4py import MPI

    warn_before_coiling(config, directory, MPI.COMM_WORLD)
    summary = run(
        config,
        directory,
        resume=args.resume,
        progress=not args.json,
        report=False if args.no_report else None,
    )
    return _finish(args, summary, directory)


def cmd_sweep(args: argparse.Namespace) -> int:
    from pathlib import Path

    from tapecoil.app.sweep import load_sweep, run_sweep

    sweep = load_sweep(args.sweep)
    directory = args.out or f"{sweep.config({}).output.directory}/sweep-{Path(args.sweep).stem}"
    summary = run_sweep(sweep, directory, progress=not args.json)
    if args.json:
        _echo(json.dumps(summary, indent=2))
    else:
        cases, groups = len(summary["cases"]), summary["groups"]
        _echo(f"sweep ({summary['study']}): {cases} cases on {groups} group(s) of ranks")
        rows = summary["cases"]
        keys = [k for k in rows[0] if k != "case"]
        _echo("  " + "  ".join(f"{k:>14}" for k in keys[:8]))
        for r in rows:
            _echo(
                "  "
                + "  ".join(
                    f"{r[k]:>14.5g}" if isinstance(r[k], float) else f"{r[k]!s:>14}" for k in keys[:8]
                )
            )
        _echo(f"  table: {directory}/sweep_summary.csv, plot: {summary['plot']}")
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    from pathlib import Path

    from tapecoil.post.report import write_report

    directory = Path(args.directory)
    if not (directory / "summary.json").is_file():
        raise ConfigError(f"{directory} is not a results directory (no summary.json in it)")
    if _rank() == 0:
        print(write_report(directory))
    return 0


def cmd_mesh(args: argparse.Namespace) -> int:
    """The configured tape's strip mesh as gmsh and XDMF files, for gmsh and ParaView."""
    from pathlib import Path

    config = _with_mesh(load_config(args.config), args.preset)  # refused before MPI starts
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
    _echo(
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
        _echo(f"  {path!s:<{max(len(str(files.surface_xdmf)), 24)}}  {what}")
    return 0


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

    p = sub.add_parser("verify", help="run the shell verification cases against their references")
    p.add_argument("case", nargs="?", default="all", choices=(*CASES, "all"))
    p.add_argument("config", nargs="?", help="TOML configuration (the tape cases use its tape)")
    p.add_argument(
        "--mesh",
        choices=("coarse", "default", "fine"),
        help="mesh preset (default: each case's coarsest that passes: default for tape-fold, else coarse)",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(func=cmd_verify)

    p = sub.add_parser("coil", help="coil the tape onto the hub to the stowed state (quasi-static)")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
    p.add_argument("--mesh", choices=("coarse", "default", "fine"), help="mesh preset (overrides the file)")
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

    p = sub.add_parser("deploy", help="deploy from a stowed checkpoint (implicit dynamics)")
    p.add_argument("stowed", help="stowed checkpoint directory (a coiling run's stowed/)")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the one beside the checkpoint)")
    p.add_argument("--out", help="results directory (default: <output.directory>/deploy)")
    p.add_argument("--resume", action="store_true", help="continue from the results directory's deployed/")
    _common_run_options(p)
    p.set_defaults(func=cmd_deploy)

    p = sub.add_parser("run", help="the whole pipeline: coil, stow, deploy")
    p.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
    p.add_argument("--mesh", choices=("coarse", "default", "fine"), help="mesh preset (overrides the file)")
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


def _common_run_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print the JSON summary (summary.json)")
    p.add_argument("--no-report", action="store_true", help="skip the pictures and report.html")


def cmd_config(args: argparse.Namespace) -> int:
    from tapecoil.config import to_toml

    _echo(to_toml(load_config(args.config)).rstrip())
    return 0


_PETSC_EPILOG = (
    "PETSc options for a solver go after tapecoil's own arguments, under the solver's prefix: "
    "coil_ (flattening and coiling), deploy_ (deployment), verify_<case>_ (the case's dashes as "
    "underscores), e.g. tapecoil coil --mesh coarse -coil_snes_monitor. They win over the "
    "configuration's petsc_options tables."
)


def _known_options(parser: argparse.ArgumentParser) -> set[str]:
    """The option strings of ``parser`` and of its commands' parsers."""
    known = set(parser._option_string_actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                known |= _known_options(sub)
    return known


def _is_value(arg: str) -> bool:
    if not arg.startswith("-"):
        return True
    try:
        float(arg)
    except ValueError:
        return False
    return True


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
            if i + 1 < len(argv) and _is_value(argv[i + 1]):
                petsc.append(argv[i + 1])
                i += 1
        else:
            ours.append(arg)
        i += 1
    return ours, petsc


def _hand_to_petsc(options: list[str]):
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


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    parser.epilog = _PETSC_EPILOG
    argv = sys.argv[1:] if argv is None else list(argv)
    ours, petsc = split_petsc_options(argv, _known_options(parser))
    args = parser.parse_args(ours)
    take_back = _hand_to_petsc(petsc)
    # a ConfigWarning is printed as one line where it is issued; Python's display would repeat it
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
