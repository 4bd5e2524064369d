"""The joint Jacobian's spectrum at the equilibrium of a tape flattened at its root, as a hybrid
(docs/notes/hybrid.md, "The flat tie's penalty"): the benchmark tape's first 0.05 m a beam of the
flattened strip's section tied flat to 0.15 m of shell, the arc-section beam beyond, 0.3 m in all,
coarse mesh, flattened by steps to 1, with the ties' penalty factor PENALTY, its tip pulled along
the tape by PULL [N] (the benchmark's coiling tension is 1 N; default 0). Prints the residual
there, the lowest eigenvalues and the highest of the Jacobian (SI, Dirichlet rows left out; dense,
one rank: about 1,300 unknowns) and their ratio, the condition number, and the same of the
Jacobian scaled by its diagonal (displacements and rotations weighed alike).

    tools/env.sh run env PYTHONPATH=solver python3 tools/hybrid_conditioning.py [PENALTY [PULL]]
"""

import sys

import numpy as np
import scipy.sparse as sp

from tapecoil.config import Config, SolverConfig
from tapecoil.verification.hybrid import tape_hybrid

penalty = float(sys.argv[1]) if len(sys.argv) > 1 else 1e3
pull = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0
hybrid, tip = tape_hybrid(Config(), 4, 0.0125, 0.3, 0.15, start=0.05, flat_root=True, penalty=penalty)
hybrid.beam.clamp((0.0, 0.0, tip[2]))
if pull:
    hybrid.beam.end_load(tip, force=(pull, 0.0, 0.0), constant=True)
hybrid.flatten("xi1_min")
hybrid.solve(1.0, first_step=0.1, max_step=0.25)

F, J = hybrid.shell.forms()
solver = hybrid._solver(F, J, SolverConfig(), None)
solver._write_states(solver.x)
solver._residual(None, solver.x, solver.r)
residual = solver.r.norm()
solver._jacobian(None, solver.x, solver.J, solver.J)
rows, columns, values = solver.J.getValuesCSR()
n = solver.J.getSize()[0]
matrix = sp.csr_matrix((values, columns, rows), shape=(n, n)).toarray()
dirichlet = [i for i in range(n) if matrix[i, i] == 1.0 and np.count_nonzero(matrix[i]) == 1]
free = np.setdiff1d(np.arange(n), dirichlet)
stiffness = matrix[np.ix_(free, free)]
stiffness = 0.5 * (stiffness + stiffness.T)
eigenvalues = np.linalg.eigvalsh(stiffness)
# scaled by the diagonal, so that displacements [m] and rotations [rad] weigh alike
scale = 1 / np.sqrt(np.abs(np.diag(stiffness)))
scaled = np.linalg.eigvalsh(stiffness * np.outer(scale, scale))
solver.destroy()
print(f"penalty factor {penalty:g}, pull {pull:g} N: residual {residual:.3g}, {len(free)} unknowns")
print("lowest eigenvalues", ", ".join(f"{v:.3g}" for v in eigenvalues[:4]), f"highest {eigenvalues[-1]:.3g}")
print(f"condition number {eigenvalues[-1] / eigenvalues[0]:.3g}")
ratio = scaled[-1] / scaled[0]
print(f"scaled by the diagonal: {scaled[0]:.3g} to {scaled[-1]:.3g}, condition number {ratio:.3g}")
