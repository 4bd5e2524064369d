"""What a full shell's Jacobian costs, part by part: the benchmark tape on the hub (a mesh
preset, default "default") with the spiral of turns of ``--hub-angle`` [rad], each energy's
Hessian (membrane, bending, shear, the whole strain, the contact, strain and contact) and the
coiling solver's Jacobian and residual assembled alone, 20 times each, on one rank; prints the
mean time of each [ms] (docs/notes/hybrid.md, "A shorter window does not make it three times
faster": the spiral's turns enter the contact's kernel).

    tools/env.sh run env PYTHONPATH=solver python3 tools/shell_kernel_cost.py [--hub-angle 141.9]
"""

import argparse
import dataclasses
import time

import dolfinx
import dolfinx.fem.petsc
import ufl
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.core import compat
from tapecoil.phases.coiling import CoilingProblem

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("mesh", nargs="?", default="default", choices=("coarse", "default", "fine"))
parser.add_argument("--hub-angle", type=float, help="coiling.hub_angle [rad] (default the benchmark's)")
args = parser.parse_args()
if MPI.COMM_WORLD.size != 1:
    raise SystemExit("time the kernels on one rank")
config = Config()
angle = config.coiling.hub_angle if args.hub_angle is None else args.hub_angle
config = dataclasses.replace(
    config,
    coiling=dataclasses.replace(config.coiling, hub_angle=angle),
    mesh=dataclasses.replace(config.mesh, preset=args.mesh),
)
model = CoilingProblem(config)
shell, solver = model.model, model.solver
REPEAT = 20


def timed(assemble) -> float:
    """Mean wall time [ms] of ``assemble()`` over REPEAT calls, after one to warm up."""
    assemble()
    t0 = time.perf_counter()
    for _ in range(REPEAT):
        assemble()
    return 1e3 * (time.perf_counter() - t0) / REPEAT


def hessian(energy):
    form = dolfinx.fem.form(
        ufl.derivative(ufl.derivative(energy, shell.q, shell.dq), shell.q, ufl.TrialFunction(shell.W))
    )
    A = dolfinx.fem.petsc.create_matrix(form)

    def assemble():
        A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(A, form)
        A.assemble()

    return assemble


parts = {
    "membrane": shell.energy_membrane,
    "bending": shell.energy_bending,
    "shear": shell.energy_shear,
    "strain": shell.strain_energy,
    "contact": model.contact.energy,
    "strain and contact": shell.strain_energy + model.contact.energy,
}
print(f"{angle:g} rad, {model.contact.max_turns} turns of the spiral, {solver.A.getSize()[0]} DOFs")
for name, energy in parts.items():
    print(f"  Hessian of {name}: {timed(hessian(energy)):.1f} ms")


def jacobian():
    solver.A.zeroEntries()
    compat.assemble_matrix(solver.A, solver.J_form, solver.bcs)
    solver.A.assemble()


print(f"  the coiling's Jacobian: {timed(jacobian):.1f} ms")
residual = timed(lambda: dolfinx.fem.petsc.assemble_vector(solver.b, solver.F_form))
print(f"  the coiling's residual: {residual:.1f} ms")
