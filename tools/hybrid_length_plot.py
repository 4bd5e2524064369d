"""The coiling's or the deployment's cost against the tape's length, hybrid beside full shell,
drawn from the JSON files of tools/hybrid_length_study.py (one per length; with ``--deploy``
there, the deployment's): wall time and DOFs against L on log axes, with the slope of each
model's wall time between successive lengths written beside it. A model missing from a file
(``--hybrid-only``) is drawn at the lengths that have it.

    tools/env.sh run python3 tools/hybrid_length_study.py ... --json L0.5.json   # per length
    tools/env.sh run python3 tools/hybrid_length_plot.py L0.5.json L1.0.json L2.0.json \\
        -o docs/images/hybrid_cost_length.png
"""

import argparse
import json
import math

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt

MODELS = {"hybrid": "hybrid (shell window + beams)", "full_shell": "full shell"}

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("results", nargs="+", help="JSON files of tools/hybrid_length_study.py")
parser.add_argument("-o", "--output", default="hybrid_cost_length.png")
args = parser.parse_args()

runs = sorted((json.load(open(path)) for path in args.results), key=lambda r: r["length"])
if len({(r["mesh"], r["ranks"], "lambda_end" in r) for r in runs}) != 1:
    raise SystemExit("the files must come from one mesh preset, one number of ranks and one phase")
deployment = "lambda_end" in runs[0]
if deployment and len({r["lambda_end"] for r in runs}) != 1:
    raise SystemExit("the deployments must stop at one deployed fraction")
lengths = [r["length"] for r in runs]

fig, (ax_time, ax_dofs) = plt.subplots(1, 2, figsize=(10, 4))
for key, label in MODELS.items():
    have = [r for r in runs if key in r]
    if not have:
        continue
    lengths = [r["length"] for r in have]
    wall = [r[key]["wall_time"] for r in have]
    ax_time.loglog(lengths, wall, "o-", label=label)
    for k in range(len(have) - 1):
        (l0, l1), (w0, w1) = lengths[k : k + 2], wall[k : k + 2]
        slope = math.log(w1 / w0) / math.log(l1 / l0)
        ax_time.annotate(
            f"L^{slope:.2f}",
            (math.sqrt(l0 * l1), math.sqrt(w0 * w1)),
            textcoords="offset points",
            xytext=(4, 6),
        )
    ax_dofs.loglog(lengths, [r[key]["dofs"] for r in have], "o-", label=label)
lengths = [r["length"] for r in runs]
phase = f"deployment to lambda = {runs[0]['lambda_end']:g}" if deployment else "coiling"
for ax, what in ((ax_time, f"wall time of the {phase} [s]"), (ax_dofs, "DOFs")):
    ax.set_xlabel("tape length L [m]")
    ax.set_ylabel(what)
    ax.set_xticks(lengths, [f"{v:g}" for v in lengths])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
first = runs[0]
title = "Deployed from a coil" if deployment else "Coiling"
fig.suptitle(
    f"{title} until 31 mm stays free, the benchmark's section and hub: {first['mesh']} mesh, "
    f"{first['ranks']} rank(s)",
    fontsize=10,
)
fig.tight_layout()
fig.savefig(args.output, dpi=120)
print(f"wrote {args.output}")
