"""A driven hub's payout by the hybrid beside the full shell's: the benchmark tape coiled to
ANGLE [rad] and paid out to lambda = LAMBDA_END by each model from its own coil, one after the
other through the pipeline (``phases=("coiling", "payout")``), on a mesh preset. Prints, for each
model, the payout's DOFs, steps, Newton iterations and wall time, the coiling's wall time, the
window's moves, and the payout's measures band by band (hub torque against steady coiling, the
outer turn's and the root's T - N against their laws); then the two side by side at the
hybrid's hub angles (the full shell's history interpolated): strain energy, coiled length,
outer coil radius and hub torque (docs/notes/hybrid.md, *A driven hub's payout by the hybrid*).

    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/hybrid_payout_study.py 36 0.9 default
"""

import argparse
import dataclasses
from pathlib import Path

import numpy as np
from mpi4py import MPI

from tapecoil.app.pipeline import run
from tapecoil.config import Config
from tapecoil.post.plots import read_history

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("angle", type=float, nargs="?", default=36.0, help="hub angle coiled [rad]")
parser.add_argument("lambda_end", type=float, nargs="?", default=0.9, help="payout.lambda_end")
parser.add_argument("mesh", nargs="?", default="default", choices=("coarse", "default", "fine"))
parser.add_argument("--out", default="results/hybrid-payout", help="results directory (one per model in it)")
args = parser.parse_args()

base = Config()
rank0 = MPI.COMM_WORLD.rank == 0
histories, summaries = {}, {}
for kind in ("hybrid", "shell"):
    config = dataclasses.replace(
        base,
        mesh=dataclasses.replace(base.mesh, preset=args.mesh),
        coiling=dataclasses.replace(base.coiling, hub_angle=args.angle),
        payout=dataclasses.replace(base.payout, lambda_end=args.lambda_end),
        model=dataclasses.replace(base.model, kind=kind),
        output=dataclasses.replace(base.output, report=False),
    )
    directory = Path(args.out) / kind
    summaries[kind] = summary = run(config, directory, phases=("coiling", "payout"), progress=False)
    histories[kind] = read_history(directory / "payout_history.csv")
    if not rank0:
        continue
    payout, coiling = summary["payout"], summary["coiling"]
    figures = payout["run"]
    print(f"{kind}: completed {payout['completed']} {payout['message']}")
    print(
        f"  payout {payout['start_hub_angle']:g} -> {payout['hub_angle']:.6g} rad, lambda "
        f"{payout['measures']['lambda_start']:.4f} -> {payout['measures']['lambda_end']:.4f}: "
        f"{figures['dofs']} DOFs, {figures['steps']} steps, {figures['newton_iterations']} Newton "
        f"iterations, {figures['wall_time']:.1f} s; coiling {coiling['run']['wall_time']:.1f} s"
    )
    if kind == "hybrid":
        print(f"  window moves back: {len(figures['windows']) - len(coiling['run']['windows'])}")
    for name, measure in payout["measures"].items():
        if isinstance(measure, dict) and "bands" in measure:
            bands = ", ".join(f"{b['lambda'][0]:.1f}: {100 * b['error']:+.1f} %" for b in measure["bands"])
            print(f"  {name}: {bands}")

if rank0:
    a, b = histories["hybrid"], histories["shell"]
    print("side by side at the hybrid's hub angles (hybrid / full shell - 1): max |.|, median |.|")
    for key in ("strain_energy", "coiled_length", "outer_radius", "hub_torque_reaction"):
        shell = np.interp(a["hub_angle"][::-1], b["hub_angle"][::-1], b[key][::-1])[::-1]
        r = np.abs(a[key] / shell - 1)
        print(f"  {key:22s} {np.nanmax(r):.2e}  {np.nanmedian(r):.2e}")
    mean = np.nanmean(a["hub_torque_reaction"]) / np.nanmean(b["hub_torque_reaction"]) - 1
    print(f"  mean hub torque over the payout: {mean:+.2e}")
    print(
        f"  at the end: strain energy {a['strain_energy'][-1] / b['strain_energy'][-1] - 1:+.2e}, "
        f"lambda {a['lambda'][-1]:.4f} against {b['lambda'][-1]:.4f}"
    )
    ratio = (
        summaries["hybrid"]["payout"]["run"]["wall_time"] / summaries["shell"]["payout"]["run"]["wall_time"]
    )
    print(f"  payout's wall time, hybrid / full shell: {ratio:.2f}")
