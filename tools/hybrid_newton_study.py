"""Newton's work in the hybrid's deployment: the tape of a configuration (TOML, default the
benchmark) coiled by the hybrid to its hub angle and deployed to ``--t-end`` [s] on a mesh preset;
prints the steps, Newton iterations, wall time, window moves, the energies at the end and the
deployed fraction at a few times, to compare settings that act on Newton (``[deployment]
rho_inf``, ``[deployment.petsc_options]`` such as ``snes_rtol`` or ``snes_linesearch_type``,
``[contact] smoothing``) at the same cost of setting up. With ``--where`` every Newton iteration
is printed with its residual split into the shell's displacements, its director angles and the
beam, and the place along and across the tape (the shell's reference coordinates) of the
largest displacement residual and of the largest director-angle update.

    tools/env.sh run env PYTHONPATH=solver python3 tools/hybrid_newton_study.py --t-end 0.1
    tools/env.sh run env PYTHONPATH=solver python3 tools/hybrid_newton_study.py settings.toml \\
        --t-end 0.03 --where
"""

import argparse
import dataclasses
import time

import numpy as np
from mpi4py import MPI

from tapecoil.config import load_config
from tapecoil.phases.hybrid_coiling import HybridCoiling
from tapecoil.phases.hybrid_deployment import HybridDeployment

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("config", nargs="?", help="TOML configuration (default: the benchmark tape)")
parser.add_argument("--mesh", default="coarse", choices=("coarse", "default", "fine"))
parser.add_argument("--t-end", type=float, default=0.1, help="deployment.t_end [s]")
parser.add_argument("--where", action="store_true", help="print every Newton iteration's residual and where")
args = parser.parse_args()

comm = MPI.COMM_WORLD
config = load_config(args.config)
config = dataclasses.replace(
    config,
    mesh=dataclasses.replace(config.mesh, preset=args.mesh),
    deployment=dataclasses.replace(config.deployment, t_end=args.t_end),
)
config.check()


def say(text: str) -> None:
    if comm.rank == 0:
        print(text, flush=True)


def gathered_max(values: np.ndarray, points: np.ndarray) -> tuple[float, np.ndarray]:
    """The largest of ``values`` over the ranks and its point (collective)."""
    k = int(np.argmax(values)) if len(values) else -1
    mine = (float(values[k]), points[k]) if k >= 0 else (-1.0, np.full(3, np.nan))
    return max(comm.allgather(mine), key=lambda item: item[0])


def watch(motion) -> None:
    """Print each Newton iteration of ``motion``'s joint solver: the residual's parts and where."""
    solver = motion.solver
    W = solver.blocks[0].q.function_space
    owned = W.dofmap.index_map.size_local * W.dofmap.index_map_bs
    parts = []
    for i in range(2):  # the displacement, the director angles
        V, dofs = W.sub(i).collapse()
        dofs = np.asarray(dofs)
        keep = dofs < owned
        bs = V.dofmap.index_map_bs
        points = V.tabulate_dof_coordinates()[np.flatnonzero(keep) // bs]
        parts.append((dofs[keep], points))

    def block(vector, k) -> np.ndarray:
        sub = vector.getSubVector(solver.index_sets[k])
        values = sub.array_r.copy()
        vector.restoreSubVector(solver.index_sets[k], sub)
        return values

    def monitor(snes, iteration, norm):
        r = snes.getFunction()[0]
        shell, beam = block(r, 0), block(r, 1)
        norms = [np.sqrt(comm.allreduce(float(np.sum(shell[d] ** 2)))) for d, _ in parts]
        norms.append(np.sqrt(comm.allreduce(float(np.sum(beam**2)))))
        largest, at = gathered_max(np.abs(shell[parts[0][0]]), parts[0][1])
        line = (
            f"  {iteration:2d} |r| {norm:.3e}: displacements {norms[0]:.2e}, angles {norms[1]:.2e}, "
            f"beam {norms[2]:.2e}; largest {largest:.2e} at {np.round(at[:2], 4)}"
        )
        if iteration > 0:
            update = block(snes.getSolutionUpdate(), 0)
            turn, where = gathered_max(np.abs(update[parts[1][0]]), parts[1][1])
            line += f"; angle update {turn:.2e} at {np.round(where[:2], 4)}"
        say(line)

    solver.snes.setMonitor(monitor)


coiling = HybridCoiling(config, comm=comm)
t0 = time.perf_counter()
coiling.flatten()
coiling.coil(config.coiling.hub_angle)
wall = time.perf_counter() - t0
say(f"coiled by the hybrid to {config.coiling.hub_angle:g} rad ({args.mesh} mesh) in {wall:.1f} s")
t0 = time.perf_counter()
deployment = HybridDeployment(coiling)
if args.where:
    watched = deployment._motion

    def motion_watched(hybrid, release):
        motion = watched(hybrid, release)
        watch(motion)
        return motion

    deployment._motion = motion_watched
    watch(deployment.motion)


def step_line(record) -> None:
    if args.where:
        say(f"step to t = {record.time:.6f} s ({record.step:.3g} s): {record.iterations} iterations")


outcome = deployment.run(step_line)
wall = time.perf_counter() - t0
records = deployment.records
times = np.array([r.time for r in records])
deployed = np.array([r.deployed for r in records])
probes = [t for t in (0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5) if t <= times[-1]]
last = records[-1]
say(
    f"deployment ({outcome}): {len(records)} steps, {sum(r.iterations for r in records)} Newton "
    f"iterations, {sum(r.cutbacks for r in records)} cut-backs, {len(deployment.moves) - 1} window "
    f"moves, {wall:.1f} s on {comm.size} rank(s)"
)
say(
    f"at t = {last.time:.6g} s: lambda {last.deployed:.6f}, strain energy {last.strain_energy:.6f} J, "
    f"kinetic {last.kinetic_energy:.6f} J"
)
if probes:
    say("lambda at t [s]: " + ", ".join(f"{t:g}: {np.interp(t, times, deployed):.6f}" for t in probes))
deployment.destroy()
