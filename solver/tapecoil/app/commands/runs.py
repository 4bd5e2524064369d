"""The commands that make or read a results directory: coil, deploy, payout, run, sweep and report."""

from __future__ import annotations

import argparse
import json

from tapecoil.app.checks import warn_before_coiling
from tapecoil.app.commands.common import echo, rank, with_mesh, with_model
from tapecoil.config import ConfigError, load_config


def _entries(measures: dict):
    """(name, the measure) of the measures that have a reference."""
    for name, value in measures.items():
        if isinstance(value, dict) and "computed" in value and "error" in value:
            yield name, value


def _measure_line(name: str, m: dict) -> str:
    """One measure on the command line: a value against its reference (and its error), or
    against the bound it must reach."""
    computed, reference = m["computed"], m["reference"]
    if computed is None:
        return f"  {name:<26} not reached; reference {reference:.5g}"
    verdict = "" if m.get("passed") is None else ("  pass" if m["passed"] else "  FAIL")
    if m.get("bound") == "lower":
        if m.get("tolerance") is None:  # a reading where the bound does not apply
            return f"  {name:<26} computed {computed:<12.5g} reported"
        return f"  {name:<26} computed {computed:<12.5g} at least  {reference:<12.5g}{verdict}"
    error = m["error"]
    return f"  {name:<26} computed {computed:<12.5g} reference {reference:<12.5g} error {error:.2%}{verdict}"


def _print_phase(name: str, phase: dict, directory) -> None:
    run = phase["run"]
    if name == "coiling":
        state = "stowed" if phase["completed"] else f"STOPPED: {phase['message']}"
        where = f"coiling to {phase['hub_angle']:.4g} of {phase['target_hub_angle']:g} rad"
    elif name == "payout":
        state = "paid out" if phase["completed"] else f"STOPPED: {phase['message']}"
        lam = phase["measures"]["lambda_end"]
        where = (
            f"payout to {phase['hub_angle']:.4g} of {phase['target_hub_angle']:.4g} rad (lambda = {lam:.3f})"
        )
    else:
        state = "deployed" if phase["completed"] else f"STOPPED: {phase['message']}"
        where = f"deployment to lambda = {phase['lambda']:.3f} at t = {phase['time']:.4g} s"
    echo(
        f"{where}: {state}\n"
        f"  mesh {run['mesh']} ({run['dofs']} dofs) on {run['ranks']} rank(s): {run['steps']} steps, "
        f"{run['newton_iterations']} Newton iterations, {run['wall_time']:.1f} s; results in {directory}"
    )
    for name_, measure in _entries(phase["measures"]):
        echo(_measure_line(name_, measure))
    if name == "payout":
        for key, value in phase["measures"].items():
            if isinstance(value, dict) and value.get("max_error") is not None:
                echo(f"  {key:<32} largest error over the lambda bands {value['max_error']:.2%}")
    if name == "deployment":
        e = phase["measures"]["energy"]
        echo(
            f"  energy: stowed {e['stowed']:.4g} J, numerically dissipated at most "
            f"{e['largest_dissipated_fraction']:.2%}, largest growth {e['largest_growth_fraction']:.2%}"
        )
        force, torque = phase.get("root_force_peak"), phase.get("root_torque_peak")
        if force and torque:
            echo(
                f"  root loads on the hub: force up to {force['value']:.4g} N (t = {force['time']:.4g} s), "
                f"torque up to {1e3 * torque['value']:.4g} N mm (t = {torque['time']:.4g} s)"
            )


def _finish(args: argparse.Namespace, summary: dict, directory) -> int:
    """Print the summary (JSON or a table) and return the exit status."""
    from tapecoil.app.pipeline import exit_status

    if args.json:
        echo(json.dumps(summary, indent=2))
    else:
        for name in ("coiling", "deployment", "payout"):
            if name in summary:
                _print_phase(name, summary[name], directory)
        if summary["interrupted"]:
            # a payout has no --resume: its checkpoint (paid_out/) is a stowed state to start from
            hint = (
                "continue with --resume" if hasattr(args, "resume") else "its last state is in the checkpoint"
            )
            echo(f"interrupted ({summary['interrupted']}): {hint}")
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

    config = with_model(with_mesh(load_config(args.config), args.mesh), args.model)
    directory = args.out or f"{config.output.directory}/coil"
    checkpoint = _resume_path(args.resume, directory, "stowed")
    from mpi4py import MPI

    from tapecoil.phases.coiling import check_free_end_room

    check_free_end_room(config)
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


def _from_stowed(args: argparse.Namespace, phase: str, checkpoint: str) -> int:
    """``phase`` from the stowed checkpoint of the command line (the command of ``args``),
    resuming with --resume from the results directory's own ``checkpoint``/."""
    from tapecoil.app.pipeline import run

    config = _stowed_config(args)
    directory = args.out or f"{config.output.directory}/{args.command}"
    if args.resume:
        _resume_path("", directory, checkpoint)
    summary = run(
        config,
        directory,
        phases=(phase,),
        resume=args.resume,
        stowed=args.stowed,
        progress=not args.json,
        report=False if args.no_report else None,
        command=args.command,
    )
    return _finish(args, summary, directory)


def cmd_deploy(args: argparse.Namespace) -> int:
    """Deploy a stowed checkpoint (implicit dynamics)."""
    return _from_stowed(args, "deployment", "deployed")


def cmd_payout(args: argparse.Namespace) -> int:
    """Pay the tape out of a stowed checkpoint with a driven hub (quasi-static)."""
    return _from_stowed(args, "payout", "paid_out")


def cmd_run(args: argparse.Namespace) -> int:
    """Coil, stow and deploy; with --resume, go on from the directory's checkpoints."""
    from tapecoil.app.pipeline import run

    config = with_model(with_mesh(load_config(args.config), args.mesh), args.model)
    directory = args.out or f"{config.output.directory}/run"
    if args.resume:
        _resume_path("", directory, "stowed")
    from mpi4py import MPI

    from tapecoil.phases.coiling import check_free_end_room

    check_free_end_room(config)
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
        echo(json.dumps(summary, indent=2))
    else:
        cases, groups = len(summary["cases"]), summary["groups"]
        echo(f"sweep ({summary['study']}): {cases} cases on {groups} group(s) of ranks")
        rows = summary["cases"]
        keys = [k for k in rows[0] if k != "case"]
        echo("  " + "  ".join(f"{k:>14}" for k in keys[:8]))
        for r in rows:
            echo(
                "  "
                + "  ".join(
                    f"{r[k]:>14.5g}" if isinstance(r[k], float) else f"{r[k]!s:>14}" for k in keys[:8]
                )
            )
        echo(f"  table: {directory}/sweep_summary.csv, plot: {summary['plot']}")
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    from pathlib import Path

    from tapecoil.post.report import write_report

    directory = Path(args.directory)
    if not (directory / "summary.json").is_file():
        raise ConfigError(f"{directory} is not a results directory (no summary.json in it)")
    if rank() == 0:
        print(write_report(directory))
    return 0
