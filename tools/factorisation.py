"""What one factorisation of Newton's matrix costs in a stowed coil, with and without the turns.

Reads a coiling checkpoint (a results directory's stowed/, any rank count), assembles the
coiling solver's matrix at the checkpoint's state (the shell, the hub and, with
``contact.turns = "surface"``, the pairs between the turns) and the shell's matrix alone, and
times MUMPS' factorisation of each for every PETSc option set given (comma-separated
key=value, no leading dash; ``-`` for MUMPS' defaults): the first one (analysis and
factorisation) and the mean of three more with the pattern kept. Prints the nonzeros, the
entries of the factors (INFOG(29)), the operations of the elimination (RINFOG(3)) and the
ordering MUMPS used (INFOG(7): 3 SCOTCH, 4 PORD, 5 METIS, ...); for another factorisation
package (``pc_factor_mat_solver_type=superlu_dist``) the times alone and the package's name.

    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/factorisation.py \\
        results/coil/stowed - mat_mumps_icntl_7=5 pc_type=cholesky
"""

import argparse
import time
from pathlib import Path

import dolfinx.fem.petsc
from mpi4py import MPI
from petsc4py import PETSc
from stowed_solver import stowed_solver

from tapecoil.core import compat

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("stowed", type=Path, help="checkpoint directory (a coiling run's stowed/)")
parser.add_argument("options", nargs="*", default=["-"], help="PETSc option sets, e.g. mat_mumps_icntl_7=5")
parser.add_argument("--repeat", type=int, default=3, help="factorisations timed after the first")
args = parser.parse_args()

comm = MPI.COMM_WORLD
model, solver = stowed_solver(args.stowed, comm)
shell = dolfinx.fem.petsc.create_matrix(solver.J_form)
compat.assemble_matrix(shell, solver.J_form, solver.bcs)
shell.assemble()
# the timed refactorisations shift the diagonal; done once here, so that a diagonal entry the
# pattern lacks is inserted before the first factorisation, not between two timed ones
for matrix in (solver.A, shell):
    matrix.shift(1e-300)


PREFIX = "factorisation_"


def option_set(text: str) -> dict:
    return {} if text == "-" else dict(item.split("=", 1) for item in text.split(","))


def factorise(matrix, options: dict) -> dict:
    database = PETSc.Options()
    for key, value in options.items():
        database[PREFIX + key] = value
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(PREFIX)
    ksp.setOperators(matrix)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setFromOptions()
    package = ksp.getPC().getFactorSolverType()
    t0 = time.perf_counter()
    ksp.setUp()
    first = time.perf_counter() - t0
    again = []
    for _ in range(args.repeat):
        matrix.shift(1e-300)  # new values, same pattern: the factorisation alone is redone
        t0 = time.perf_counter()
        ksp.setOperators(matrix)
        ksp.setUp()
        again.append(time.perf_counter() - t0)
    factors = ksp.getPC().getFactorMatrix()
    out = {
        "first": comm.allreduce(first, op=MPI.MAX),
        "again": comm.allreduce(sum(again) / max(len(again), 1), op=MPI.MAX),
        "factor_entries": factors.getMumpsInfog(29) if package == "mumps" else -1,
        "operations": factors.getMumpsRinfog(3) if package == "mumps" else float("nan"),
        "ordering": factors.getMumpsInfog(7) if package == "mumps" else package,
    }
    ksp.destroy()
    for key in options:
        database.delValue(PREFIX + key)
    return out


for name, matrix in (("coiling solver", solver.A), ("shell alone", shell)):
    nonzeros = matrix.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"]
    for text in args.options:
        r = factorise(matrix, option_set(text))
        if comm.rank == 0:
            print(
                f"{name:15s} {text:40s} nonzeros {nonzeros:10.0f}  factors {r['factor_entries']:10d}"
                f"  operations {r['operations']:8.2e}  ordering {r['ordering']}"
                f"  first {r['first']:.3f} s  again {r['again']:.3f} s",
                flush=True,
            )
