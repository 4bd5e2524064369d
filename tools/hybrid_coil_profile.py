"""Where the hybrid's coiling spends its time: the benchmark tape (or ``--angle`` [rad] of it)
flattened and coiled by the hybrid under cProfile, then the cumulative times of its Newton
solves, Jacobians and residuals, window builds and carry-overs, and of the forms created, with
their callers (docs/notes/hybrid.md, "Where the time goes"). Under mpirun, rank 0's.

    tools/env.sh run env PYTHONPATH=solver python3 tools/hybrid_coil_profile.py [--angle 36]
    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/hybrid_coil_profile.py --angle 6
"""

import argparse
import cProfile
import dataclasses
import pstats

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.phases.hybrid_coiling import HybridCoiling

WATCHED = (
    r"coupled_newton.py.*\((solve|_jacobian|_residual|__init__)\)"
    r"|hybrid_coiling.py.*\((coil|flatten|_build)\)|window.py.*\(carry_over\)|forms.py.*\(form\)"
)

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--angle", type=float, default=None, help="hub angle [rad] (default: the benchmark's)")
args = parser.parse_args()
config = Config()
angle = config.coiling.hub_angle if args.angle is None else args.angle
config = dataclasses.replace(config, coiling=dataclasses.replace(config.coiling, hub_angle=angle))

profile = cProfile.Profile()
profile.enable()
coiling = HybridCoiling(config)
coiling.flatten()
coiling.coil(angle)
profile.disable()
if MPI.COMM_WORLD.rank != 0:
    raise SystemExit(0)
print(
    f"{angle:g} rad: {len(coiling.records)} steps, "
    f"{sum(r.iterations for r in coiling.records)} Newton iterations, {len(coiling.moves) - 1} moves"
)
stats = pstats.Stats(profile)
stats.sort_stats("cumulative").print_stats(WATCHED)
stats.print_callers(r"forms.py.*\(form\)")
