"""``tapecoil fold``: the configured tape spring's moment-rotation curve in both senses of
bending (:mod:`tapecoil.verification.moment_rotation`), as a table, a CSV and a plot."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from tapecoil.app.commands.common import echo, rank
from tapecoil.config import load_config


def cmd_fold(args: argparse.Namespace) -> int:
    config = load_config(args.config)
    from tapecoil.verification.moment_rotation import ANGLE_RANGE, END_ANGLE, SENSES

    angle = END_ANGLE if args.angle is None else args.angle
    lo, hi = ANGLE_RANGE
    tp = config.tape
    refused = None
    if not (math.isfinite(angle) and lo < angle <= hi):
        refused = (
            f"--angle {angle} rad: the end rotation must lie in ({lo:g}, pi]; beyond pi the tape's arms "
            "would pass through each other"
        )
    elif args.length is not None and not (math.isfinite(args.length) and 0 < args.length <= tp.L):
        refused = f"--length {args.length} m: must lie in (0, tape.L = {tp.L:g}] m"
    if refused:
        if rank() == 0:
            print(f"tapecoil: fold: {refused}", file=sys.stderr)
        return 2
    senses = SENSES if args.sense == "both" else (args.sense,)

    from tapecoil.core.arclength import ArcLengthError
    from tapecoil.core.stepping import ContinuationError
    from tapecoil.post.paths import moment_rotation_files
    from tapecoil.verification.moment_rotation import tape_moment_rotation

    try:
        result = tape_moment_rotation(config, args.mesh, length=args.length, end_angle=angle, senses=senses)
    except (ContinuationError, ArcLengthError) as exc:
        if rank() == 0:
            print(f"tapecoil: fold stopped: {exc}", file=sys.stderr, flush=True)
        return 1
    directory = Path(args.out or f"{config.output.directory}/fold")
    if rank() == 0:
        directory.mkdir(parents=True, exist_ok=True)
        files = moment_rotation_files(
            result.info["senses"], directory, f"{result.info['mesh']}, {args.mesh} mesh"
        )
        summary = {
            sense: {k: v for k, v in curve.items() if k != "rows"}
            for sense, curve in result.info["senses"].items()
        }
        (directory / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
    if args.json:
        echo(json.dumps(summary if rank() == 0 else {}, indent=2, default=float))
        return 0
    info = result.info
    echo(f"moment-rotation of a {info['length']:.4g} m piece, {info['mesh']}, {info['dofs']} dofs")
    for sense, c in result.info["senses"].items():
        ratio = c["steady_fold_moment"] / c["fold_moment_reference"]
        echo(f"{sense} sense ({c['wall_time']:.0f} s)")
        echo(f"  peak moment                    {c['peak_moment']:.4g} N m at {c['peak_rotation']:.4g} rad")
        kind = f"snap ({c['snap_kind']})"
        echo(f"  {kind:<30} at {c['snap_rotation']:.4g} rad, {c['snap_moment']:.4g} N m")
        echo(
            f"  fold vanishes (limit point)    at {c['fold_vanishes_rotation']:.4g} rad, "
            f"{c['fold_vanishes_moment']:.4g} N m"
        )
        sign = "+" if sense == "opposite" else "-"
        echo(
            f"  steady fold moment             {c['steady_fold_moment']:.4g} N m, {ratio:.3f} of "
            f"alpha (sqrt(D11 D22) {sign} D12) = {c['fold_moment_reference']:.4g} N m, "
            f"{c['steady_fold_moment'] / c['fold_moment_with_edges']:.3f} of it with the edge layers"
        )
    if rank() == 0:
        for path in files:
            echo(f"wrote {path}")
    return 0
