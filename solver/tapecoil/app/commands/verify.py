"""``tapecoil verify``: the shell's, the beam's and the hybrid's verification cases against their
references."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tapecoil.app.commands.common import echo, rank
from tapecoil.config import load_config


def cmd_verify(args: argparse.Namespace) -> int:
    import time

    config = load_config(args.config)
    from tapecoil.core.arclength import ArcLengthError
    from tapecoil.core.stepping import ContinuationError
    from tapecoil.verification import CASES, not_applicable
    from tapecoil.verification.cases import run_case

    names = CASES if args.case == "all" else (args.case,)
    if args.case != "all" and (reason := not_applicable(args.case, config)):
        if rank() == 0:
            print(f"tapecoil: {args.case} cannot run: {reason}", file=sys.stderr, flush=True)
        return 2
    results, stopped = [], {}
    for name in names:
        if reason := not_applicable(name, config):
            if rank() == 0:
                print(f"tapecoil: {name} skipped: {reason}", file=sys.stderr, flush=True)
            continue
        t0 = time.perf_counter()
        try:
            result = run_case(name, config, args.mesh)
        except (ContinuationError, ArcLengthError) as exc:
            # a case whose solve fails is a failed case with its reason, not a traceback; the
            # other cases still run
            stopped[name] = str(exc)
            if rank() == 0:
                print(f"tapecoil: {name} stopped: {exc}", file=sys.stderr, flush=True)
            continue
        result.info["case_wall_time"] = time.perf_counter() - t0
        results.append(result)
        files = case_files(result, args.out or f"{config.output.directory}/verify") if rank() == 0 else []
        if not args.json:
            mesh, wall = result.info.get("mesh", ""), result.info["case_wall_time"]
            echo(f"{name} ({result.info['preset']} mesh, {mesh}, {wall:.1f} s)")
            for c in result.checks:
                err = f"{c.error:.2e}" + ("" if c.absolute else " rel")
                echo(
                    f"  {c.name:<40} computed {c.computed:<12.6g} reference {c.reference:<10.6g} "
                    f"error {err:<13} tol {c.tolerance:g}  {'PASS' if c.passed else 'FAIL'}"
                )
            for what, value in result.info.get("predictions", ()):
                echo(f"  {what:<40} computed {value:<12.6g} (a prediction: no reference)")
            for path in files:
                echo(f"  wrote {path}")
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
        payload += [{"case": name, "passed": False, "stopped": reason} for name, reason in stopped.items()]
        echo(json.dumps(payload, indent=2, default=float))
    return 0 if all(r.passed for r in results) and not stopped else 1


def _moment_rotation_files(result, directory: Path) -> list:
    from tapecoil.post.paths import moment_rotation_files

    return moment_rotation_files(result.info["senses"], directory, f"{result.case} ({result.info['mesh']})")


def _roof_files(result, directory: Path) -> list:
    from tapecoil.post.paths import roof_files
    from tapecoil.verification.roof import SZE_PMAX, SZE_ROOF_LIMIT

    ratio, w = SZE_ROOF_LIMIT[result.info["thickness"]]
    return roof_files(result.case, result.info, (ratio * SZE_PMAX, w), directory)


# the cases that follow a path write its curve (CSV and plot): the roof's load-deflection, the
# tape's moment-rotation
CURVE_FILES = {
    "tape-moment-rotation": _moment_rotation_files,
    "roof-snap-through": _roof_files,
    "roof-snap-back": _roof_files,
}


def case_files(result, directory) -> list:
    """The curves of a case that follows a path, as a CSV and a plot into ``directory``
    (:data:`CURVE_FILES`); none for the other cases. Serial."""
    writer = CURVE_FILES.get(result.case)
    return [] if writer is None else writer(result, Path(directory))
