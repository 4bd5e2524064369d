import dataclasses, json
from mpi4py import MPI
from tapecoil.config import load_config
from tapecoil.phases.deployment_run import run_deployment
cfg = load_config("/work/main/.scratch/run-coarse/config.toml")
cfg = dataclasses.replace(cfg, output=dataclasses.replace(cfg.output, report=False, vtx_every=1000))
s, _ = run_deployment(cfg, "/work/main/.scratch/wt/.coarse-out", stowed="/work/main/.scratch/run-coarse/stowed", progress=False)
if MPI.COMM_WORLD.rank == 0:
    print(json.dumps(s["measures"]["energy"], indent=1), s["run"]["steps"], s["run"]["newton_iterations"], s["run"]["wall_time"])
