"""Compare the numbers of two results directories (a refactoring changes none of them).

    python3 tools/compare_results.py OLD_DIR NEW_DIR [--rtol 1e-6] [--atol 1e-10]

Compares summary.json (every number, by its path: phase, measure, field; relative to the
number) when both directories have one, and every *_history.csv (each numeric column step by
step, relative to the column's largest magnitude, so that a quantity passing through zero, a
tip position say, is not judged by its round-off), and with an absolute floor ``atol`` in SI
units (a quantity that is zero by symmetry is round-off on both sides).
Wall times, timings per iteration and the tapecoil version are skipped: they change from run to
run. Prints what differs by more than rtol, what one side lacks, and a count; exits 1 if any
number differs.
"""

import argparse
import csv
import json
import math
import sys
from pathlib import Path

SKIPPED = ("wall_time", "per_iteration", "tapecoil", "case_wall_time")


def leaves(value, path=()):
    if isinstance(value, dict):
        for key, item in value.items():
            yield from leaves(item, (*path, str(key)))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from leaves(item, (*path, str(i)))
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield "/".join(path), float(value)


def history(path: Path) -> tuple[dict, dict]:
    """(path -> value, path -> the scale it is compared at: its column's largest magnitude)."""
    with path.open() as f:
        rows = list(csv.DictReader(f))
    out, column = {}, {}
    for i, row in enumerate(rows):
        for key, text in row.items():
            try:
                out[f"{path.name}/{i}/{key}"] = value = float(text)
            except (TypeError, ValueError):
                continue
            column[key] = max(column.get(key, 0.0), abs(value))
    return out, {p: column[p.rsplit("/", 1)[1]] for p in out}


def numbers(directory: Path, names: set[str]) -> tuple[dict, dict]:
    out, scales = {}, {}
    if "summary.json" in names:
        out.update(leaves(json.loads((directory / "summary.json").read_text()), ("summary",)))
    for name in sorted(n for n in names if n.endswith("_history.csv")):
        values, columns = history(directory / name)
        out.update(values)
        scales.update(columns)
    return {p: v for p, v in out.items() if not any(s in p for s in SKIPPED)}, scales


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--rtol", type=float, default=1e-6)
    parser.add_argument("--atol", type=float, default=1e-10)
    args = parser.parse_args()
    names = {p.name for p in args.old.iterdir()} & {p.name for p in args.new.iterdir()}
    (old, old_scales), (new, new_scales) = numbers(args.old, names), numbers(args.new, names)
    differ, worst = 0, 0.0
    for path in sorted(old.keys() & new.keys()):
        a, b = old[path], new[path]
        if math.isnan(a) and math.isnan(b):
            continue
        scale = max(abs(a), abs(b), old_scales.get(path, 0.0), new_scales.get(path, 0.0))
        if abs(a - b) > args.rtol * scale + args.atol:
            differ += 1
            print(f"differs   {path}: {a!r} -> {b!r} ({abs(a - b) / scale:.2e})")
        elif abs(a - b) > args.atol:
            worst = max(worst, abs(a - b) / scale)
    for path in sorted(old.keys() - new.keys()):
        print(f"only old  {path}")
    for path in sorted(new.keys() - old.keys()):
        print(f"only new  {path}")
    compared = len(old.keys() & new.keys())
    print(
        f"{compared} numbers compared, {differ} differ by more than {args.rtol:g} "
        f"(the largest relative difference above atol within it: {worst:.1e})"
    )
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
