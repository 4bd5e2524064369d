"""The coiling's cost against the tape's length, hybrid beside full shell: the benchmark tape's
section and hub at length L [m] (argument), coiled until FREE [m] of it stays off the coil
(the hub angle from the theory's spiral), by the hybrid and by the full shell one after the
other (`tapecoil.verification.hybrid_coil.coil_side_by_side`), on a mesh preset (second argument,
default "default"). Prints the hub angle and, for both models, the stored energy, coiled
length, outer radius, outer turn's coiling tension, free part's height, DOFs, steps, Newton
iterations and wall time (docs/hybrid.md, "Cost against the tape's length"); ``--json FILE``
also writes them there, for tools/hybrid_length_plot.py.

    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/hybrid_length_study.py 1.0
"""

import argparse
import dataclasses
import json

from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import Config
from tapecoil.verification.hybrid_coil import coil_side_by_side

FREE = 0.031  # [m] the benchmark's 0.5 m at 36 rad leaves 31 mm off the coil

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("length", type=float, help="tape length L [m]")
parser.add_argument("mesh", nargs="?", default="default", choices=("coarse", "default", "fine"))
parser.add_argument("--json", help="write the results to this file as well")
args = parser.parse_args()
if not args.length > 2 * FREE:
    raise SystemExit(f"the tape must be longer than {2 * FREE} m, got {args.length}")

config = Config()
angle = theory.rotation_for_coiled_length(args.length - FREE, config.hub.radius, config.tape.h)
config = dataclasses.replace(
    config,
    tape=dataclasses.replace(config.tape, L=args.length),
    coiling=dataclasses.replace(config.coiling, hub_angle=angle),
)
both = coil_side_by_side(config, args.mesh, angle)
if MPI.COMM_WORLD.rank == 0:
    print(
        f"L = {args.length:g} m, hub angle {angle:.4g} rad, mesh {args.mesh}, {MPI.COMM_WORLD.size} rank(s)"
    )
    print(f"{'':<26} {'hybrid':>14} {'full shell':>14} {'hybrid / full':>14}")
    for key, value in both["hybrid"].items():
        full = both["full_shell"][key]
        ratio = f"{value / full:>14.5f}" if value is not None and full else ""
        cells = [f"{v:>14.6g}" if v is not None else f"{'-':>14}" for v in (value, full)]
        print(f"{key:<26} {cells[0]} {cells[1]} {ratio}")
    print(f"window moves: {len(both['windows']) - 1}")
    if args.json:
        record = {"length": args.length, "hub_angle": angle, "mesh": args.mesh, "ranks": MPI.COMM_WORLD.size}
        with open(args.json, "w") as f:
            json.dump({**record, **both}, f, indent=1)
