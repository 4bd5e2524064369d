"""The hybrid's window reach against its cost and accuracy: the benchmark tape (default mesh)
coiled and deployed to lambda = 0.95 by the hybrid with ``model.window_ahead`` = AHEAD [m];
prints the coiling's wall time and steps, the deployment's wall time, steps, Newton iterations,
DOFs (the window at its longest) and window moves, the time to lambda = 0.9 and the stowed
energy (docs/notes/hybrid.md, "A shorter window does not make it three times faster"). Run two reaches
one after the other, alternated, to compare their costs in one session.

    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/hybrid_window_reach.py 0.1
"""

import argparse
import dataclasses

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.verification.hybrid_deploy import deploy_side_by_side, time_to

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("ahead", type=float, help="model.window_ahead [m]")
parser.add_argument("--mesh", default="default", choices=("coarse", "default", "fine"))
args = parser.parse_args()

config = Config()
config = dataclasses.replace(
    config,
    model=dataclasses.replace(config.model, kind="hybrid", window_ahead=args.ahead),
    deployment=dataclasses.replace(config.deployment, lambda_end=0.95),
)
config.check()
result = deploy_side_by_side(config, args.mesh, config.coiling.hub_angle, full_shell=False)
h = result["hybrid"]
if MPI.COMM_WORLD.rank == 0:
    print(
        f"window_ahead {args.ahead:g} m: coiling {h['coiling_wall_time']:.1f} s, {h['coiling_steps']} "
        f"steps; deployment {h['wall_time']:.1f} s, {h['steps']} steps, {h['newton_iterations']} Newton "
        f"iterations, {h['dofs']} DOFs, {len(result['moves']) - 1} window moves; time to lambda = 0.9 "
        f"{time_to(h, 0.9):.6f} s; stowed energy {h['strain_energy'][0]:.6f} J; stopped: {h['stopped']}"
    )
