"""The coiling tension from the coil's energy alone: kappa dU/dkappa - U on three hubs.

The configurational balance T = kappa dU/dkappa - U (physics brief Sec. 5) needs the coil's
energy per unit length U as a function of its curvature kappa = 1/rho. This tool coils the same
piece (the coiling-tension study's: --length m coiled --angle rad, T = Eq. 2.6 at r_c + 0.6 N)
on hubs r_c/R = ratio - delta, ratio, ratio + delta, reads U on the steady stretch --stretch
(winding angles from the root) with measures.coil_section, and differentiates it by three
points. Printed beside it: the same tension across the coil's sections at the middle hub, and
Eq. 2.6 with and without the free edges' layers (theory.edge_layer).

    tools/env.sh run python3 tools/coil_energy_balance.py --ratio 0.9
    tools/env.sh run python3 tools/coil_energy_balance.py --config demos/coiling_tension_steel.toml
    tools/env.sh run python3 tools/coil_energy_balance.py --ratio 0.8 --element-size 0.002
"""

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import tomllib
from mpi4py import MPI

from tapecoil import theory
from tapecoil.app.sweep import load_sweep
from tapecoil.config import config_from_dict, load_config
from tapecoil.measures.coil_section import CoilSection
from tapecoil.phases.coiling import CoilingProblem
from tapecoil.phases.coiling_run import CoilingRun

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--config", default="", help="a configuration or sweep TOML (default: the benchmark)")
parser.add_argument("--ratio", type=float, default=0.9, help="middle hub's r_c/R")
parser.add_argument("--delta", type=float, default=0.05, help="step in r_c/R to the other two hubs")
parser.add_argument("--length", type=float, default=0.2, help="length of the piece [m]")
parser.add_argument("--angle", type=float, default=5.5, help="hub angle coiled [rad]")
parser.add_argument("--stretch", type=float, nargs=2, default=(1.0, 3.5), help="winding angles [rad]")
parser.add_argument(
    "--element-size", type=float, default=0.0, help="element length along the tape [m] (0: the preset's)"
)
args = parser.parse_args()

if args.config and "sweep" in tomllib.loads(Path(args.config).read_text()):
    base = config_from_dict(load_sweep(args.config).base)  # a sweep's base case
else:
    base = load_config(args.config or None)
comm = MPI.COMM_WORLD
tp, wall = dataclasses.replace(base.tape, L=args.length), base.wall
stiffness = wall.axial_stiffness
curvature, energy = [], []
for ratio in (args.ratio - args.delta, args.ratio, args.ratio + args.delta):
    r_c = ratio * tp.R
    pull = theory.coiling_tension_bending(wall.bending, tp.alpha, tp.R, r_c) + 0.6
    case = dataclasses.replace(
        base,
        tape=tp,
        hub=dataclasses.replace(base.hub, radius=r_c),
        coiling=dataclasses.replace(base.coiling, hub_angle=args.angle, tension=pull),
        contact=dataclasses.replace(base.contact, smoothing=0.0),
        mesh=dataclasses.replace(base.mesh, element_size=args.element_size or base.mesh.element_size),
    )
    model = CoilingProblem(case, comm)
    run = CoilingRun(model, max_step=0.05)
    run.flatten()
    run.coil(args.angle)
    section = CoilSection(model.tape)
    curvature.append(1.0 / (r_c + tp.h / 2))
    energy.append(section.energy_per_length(tuple(args.stretch)))
    if ratio == args.ratio:
        across = model.edge_forces()["tension"] - section.axial_force(tuple(args.stretch)).mean()
    model.solver.destroy()

k, U = np.array(curvature), np.array(energy)
right, left = (U[0] - U[1]) / (k[0] - k[1]), (U[1] - U[2]) / (k[1] - k[2])
slope = (right * (k[1] - k[2]) + left * (k[0] - k[1])) / (k[0] - k[2])  # the parabola's, at k[1]
balance = k[1] * slope - U[1]
rho = 1.0 / k[1]
plate = theory.coiling_tension_bending(wall.bending, tp.alpha, tp.R, rho)
edges = theory.coiling_tension_with_edges(wall.bending, stiffness, tp.alpha, tp.R, rho)
if comm.rank == 0:
    for ratio, ki, ui in zip(
        (args.ratio - args.delta, args.ratio, args.ratio + args.delta), k, U, strict=True
    ):
        print(f"r_c/R = {ratio:.3f}: kappa = {ki:.3f} 1/m, U = {ui:.5f} J/m on {args.stretch} rad")
    print(f"at r_c/R = {args.ratio}: kappa dU/dkappa - U = {balance:.4f} N")
    print(f"  across the coil's sections: {across:.4f} N")
    print(f"  Eq. 2.6: {plate:.4f} N; Eq. 2.6 + the edges' layers: {edges:.4f} N")
