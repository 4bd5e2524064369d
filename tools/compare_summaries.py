"""Compare the numbers of two results directories' summary.json (a refactoring changes none).

    python3 tools/compare_summaries.py OLD/summary.json NEW/summary.json [--rtol 1e-6]

Every number in both files is compared by its path (phase, measure, field); wall times, timings
per iteration and the tapecoil version are skipped, as they change from run to run. Prints the
paths whose relative difference exceeds rtol, the paths present in one file only, and a count;
exits 1 if any number differs.
"""

import argparse
import json
import math
import sys

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


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--rtol", type=float, default=1e-6)
    args = parser.parse_args()
    old, new = (
        {p: v for p, v in leaves(json.load(open(f))) if not any(s in p for s in SKIPPED)}
        for f in (args.old, args.new)
    )
    differ = 0
    for path in sorted(old.keys() & new.keys()):
        a, b = old[path], new[path]
        if math.isnan(a) and math.isnan(b):
            continue
        scale = max(abs(a), abs(b))
        if scale > 0 and abs(a - b) > args.rtol * scale:
            differ += 1
            print(f"differs   {path}: {a!r} -> {b!r} ({abs(a - b) / scale:.2e})")
    for path in sorted(old.keys() - new.keys()):
        print(f"only old  {path}")
    for path in sorted(new.keys() - old.keys()):
        print(f"only new  {path}")
    print(f"{len(old.keys() & new.keys())} numbers compared, {differ} differ by more than {args.rtol:g}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
