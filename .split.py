import sys, dataclasses, numpy as np, time
sys.path.insert(0, "/work/main/.scratch/wt/tests")
from test_deployment import short_stowed_config, coil, deploy
from mpi4py import MPI
for rho in (0.5, 1.0):
    config = short_stowed_config(t_end=0.012, rho_inf=rho)
    st = coil(config, MPI.COMM_SELF)
    _, r = deploy(st, config)
    h = r.history; E = h[0]["strain_energy"] + h[0]["contact_energy"]
    for key in ("dissipated_energy", "scheme_dissipation", "residual_work", "contact_update_energy"):
        v = np.array([x[key] for x in h]) / E
        print(rho, key, "final %.3e min %.3e max %.3e" % (v[-1], v.min(), v.max()), "min step diff %.3e" % np.diff(v).min())
