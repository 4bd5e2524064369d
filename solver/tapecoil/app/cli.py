"""Command line: ``tapecoil theory [config.toml] [--json]`` and the simulation commands.

Configuration errors are reported as one line naming the key and the allowed range, with
exit status 2, before anything is computed. Output is printed by MPI rank 0 only.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from tapecoil import __version__
from tapecoil.config import ConfigError, load_config


def _rank() -> int:
    try:
        from mpi4py import MPI
    except ImportError:  # the theory report does not need MPI
        return 0
    return MPI.COMM_WORLD.rank


def _echo(text: str = "") -> None:
    if _rank() == 0:
        print(text, flush=True)


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
    from tapecoil.verification.cases import CASES, run_case

    names = CASES if args.case == "all" else (args.case,)
    results = []
    for name in names:
        t0 = time.perf_counter()
        result = run_case(name, config, args.mesh)
        result.info["case_wall_time"] = time.perf_counter() - t0
        results.append(result)
        if not args.json:
            mesh, wall = result.info.get("mesh", ""), result.info["case_wall_time"]
            _echo(f"{name} ({args.mesh} mesh, {mesh}, {wall:.1f} s)")
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

    from tapecoil.verification.cases import CASES

    p = sub.add_parser("verify", help="run the shell verification cases against their references")
    p.add_argument("case", nargs="?", default="all", choices=(*CASES, "all"))
    p.add_argument("config", nargs="?", help="TOML configuration (the tape cases use its tape)")
    p.add_argument("--mesh", default="coarse", choices=("coarse", "default", "fine"))
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


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except ConfigError as exc:
        print(f"tapecoil: configuration error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
