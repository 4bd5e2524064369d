"""The release's wave down the coil, hybrid beside full shell: the benchmark tape (default mesh)
coiled to 36 rad by the hybrid and let go, by the hybrid (its window at release holding
``--window-release`` [m] of coil behind the lift-off, by default the configuration's
model.window_release) and, from the hybrid's coil settled in it, by the full shell, to t = T_END
[s] (argument, default 0.011). At stations along the coil the inner face's largest gap across the strip to the
spiral of turns beneath (the shell contact's nodal penetration, negated: the same measure in
both models) is followed step by step; printed: each station's peak gap [h] and when it came
[ms], for both models, and the hybrid's reading behind its window (the flattened beam's largest gap to its
turn, where it stops at 2 h: ``CoilLoosening``, which ends the hybrid's part and is printed)
with where and when it was largest (docs/notes/hybrid.md, "The release's wave and the window's
length"). ``--error-tolerance`` and ``--max-dt`` set the deployment's steps.

    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/release_wave.py
"""

import argparse
import dataclasses

import numpy as np
from mpi4py import MPI

from tapecoil.config import load_config
from tapecoil.phases.coiling import CoilingProblem
from tapecoil.phases.deployment import DeploymentProblem
from tapecoil.phases.deployment_run import DeploymentRun
from tapecoil.phases.hybrid_coiling import HybridCoiling
from tapecoil.phases.hybrid_coiling_run import settle
from tapecoil.phases.hybrid_deployment import CoilLoosening, HybridDeployment

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("t_end", nargs="?", type=float, default=0.011, help="simulated time [s]")
parser.add_argument(
    "--stations",
    type=float,
    nargs="+",
    default=[0.32, 0.34, 0.36, 0.38, 0.40, 0.42, 0.44],
    help="material coordinates along the tape [m] (on the shell's nodes)",
)
parser.add_argument(
    "--window-release",
    type=float,
    help="model.window_release [m]: the coil the hybrid's window holds behind the lift-off at "
    "release (0.025 keeps the coiling's window)",
)
parser.add_argument(
    "--error-tolerance", type=float, default=0.0, help="deployment.error_tolerance (0: the default steps)"
)
parser.add_argument("--max-dt", type=float, help="deployment.max_dt and dt [s]")
args = parser.parse_args()
comm = MPI.COMM_WORLD
config = load_config()
steps = {"error_tolerance": args.error_tolerance}
if args.max_dt is not None:
    steps.update(max_dt=args.max_dt, dt=args.max_dt)
config = dataclasses.replace(
    config,
    mesh=dataclasses.replace(config.mesh, preset="default"),
    deployment=dataclasses.replace(config.deployment, t_end=args.t_end, **steps),
)
if args.window_release is not None:
    config = dataclasses.replace(
        config, model=dataclasses.replace(config.model, window_release=args.window_release)
    )
h = config.tape.h
stations = np.asarray(args.stations)


def gaps(shell) -> np.ndarray:
    """The largest gap of the inner face to its obstacle across the strip at each station [m]
    (NaN where the shell has no node; collective)."""
    nodes = shell.contact.nodes
    owned = nodes.space.dofmap.index_map.size_local
    gap = -shell.contact.nodal_penetration()[:owned]
    s = nodes.xi[0, :owned]
    local = np.full(len(stations), -np.inf)
    for k, station in enumerate(stations):
        at = np.abs(s - station) < 1e-6 * config.tape.L
        if at.any():
            local[k] = gap[at].max()
    largest = np.empty_like(local)
    comm.Allreduce(local, largest, op=MPI.MAX)
    return np.where(np.isfinite(largest), largest, np.nan)


def follow(times: list, rows: list, t: float, shell) -> None:
    times.append(t)
    rows.append(gaps(shell))


coiling = HybridCoiling(config, comm)
coiling.flatten()
coiling.coil(config.coiling.hub_angle)
hybrid = HybridDeployment(coiling)
if comm.rank == 0:
    print(f"the hybrid's window at release: {hybrid.window()[0]:.4f} to {hybrid.window()[1]:.4f} m")
sides = {"hybrid": ([], []), "full shell": ([], [])}
follow(*sides["hybrid"], 0.0, hybrid.hybrid.shell)
behind = (0.0, 0.0, 0.0)  # the beam's largest gap behind the window [m], where [m], when [s]


def hybrid_step(record) -> None:
    global behind
    follow(*sides["hybrid"], record.time, hybrid.hybrid.shell)
    gap, at = hybrid.beam_gap
    if gap > behind[0]:
        behind = (gap, at, record.time)


try:
    hybrid.run(hybrid_step)
except CoilLoosening as stop:
    if comm.rank == 0:
        print(f"the hybrid stopped: {stop}")
hybrid.destroy()
if comm.rank == 0:
    print(
        f"the flattened beam behind the window: largest gap {behind[0] / h:.2f} h at s = "
        f"{behind[1]:.3f} m, t = {1e3 * behind[2]:.2f} ms"
    )

model = CoilingProblem(config, comm)
coiling.carry_into(model)
settle(model, coiling.angle)
follow(*sides["full shell"], 0.0, model.tape)
DeploymentRun(
    DeploymentProblem(model.tape, config),
    on_step=lambda row: follow(*sides["full shell"], row["time"], model.tape),
).run()

if comm.rank == 0:
    print(f"release of the benchmark (36 rad, default mesh, {comm.size} rank(s)) to t = {args.t_end:g} s")
    print("station [m]   " + "   ".join(f"{name:>22}" for name in sides))
    peaks = {}
    for name, (times, rows) in sides.items():
        values = np.array(rows)
        peaks[name] = [
            (np.nan, np.nan)
            if np.all(np.isnan(values[:, k]))
            else (values[np.nanargmax(values[:, k]), k] / h, 1e3 * times[np.nanargmax(values[:, k])])
            for k in range(len(stations))
        ]
    for k, station in enumerate(stations):
        cells = [f"{g:7.2f} h at {t:6.2f} ms" for g, t in (peaks[name][k] for name in sides)]
        print(f"{station:<13.3f} " + "   ".join(f"{c:>22}" for c in cells))
