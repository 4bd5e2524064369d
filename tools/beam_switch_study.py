"""A tape coiled as a beam alone: the arc section ahead of the wound length, the flattened
strip behind it (docs/notes/beam.md, "A beam alone does not make the ploy region").

The benchmark tape (physics brief Sec. 1) as a beam of ELEMENTS elements along LENGTH [m], its
root clamped to the 12.7 mm hub and turned by WRAP pi [rad], a 1 N pull held along a guide
that also holds the end's rotation; after each step the elements behind rho psi take the
flattened strip's section. Prints T - N, N read from the strains over the middle of the wrap,
against Eq. 2.6.

    tools/env.sh run env PYTHONPATH=solver python3 tools/beam_switch_study.py [ELEMENTS LENGTH WRAP]
"""

import math
import sys

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.models.beam_problem import BeamProblem
from tapecoil.models.beam_section import BeamSection
from tapecoil.verification.beam import fixed_frame, straight_line

R, alpha, h, E, nu = 0.0151, 2.3562, 1e-4, 1.3e11, 0.3
b, D = R * alpha, E * h**3 / (12 * (1 - nu**2))
rho = 0.0127 + h / 2  # the flattened strip's mid-surface on the hub
elements = int(sys.argv[1]) if len(sys.argv) > 1 else 100
length = float(sys.argv[2]) if len(sys.argv) > 2 else 0.3
wrap = float(sys.argv[3]) * math.pi if len(sys.argv) > 3 else 1.5 * math.pi
pull = 1.0
arc = BeamSection.circular_arc(R, alpha, h, E, nu)
flat = BeamSection.flattened_strip(D, nu * D, D, R, b, h, E, nu)
eq_2_6 = b * D / 2 * (1 / rho**2 - 1 / R**2)

problem = BeamProblem(straight_line, length, elements, arc, fixed_frame)
centre, axis = (0, 0, -rho), (0, -1, 0)
problem.clamp((0, 0, 0), turning_about=(centre, axis))
problem.hold((length, 0, 0), (1, 2), rotation=True)
problem.end_load((length, 0, 0), force=(pull, 0, 0), constant=True)
problem.hub_contact(centre, axis, rho, penalty=1e8)
owned = np.arange(problem.mesh.topology.index_map(1).size_local, dtype=np.int32)
middle = dolfinx.mesh.compute_midpoints(problem.mesh, 1, owned)[:, 0]


def switch(step):
    problem.model.set_section(owned[middle < rho * step.load], flat)


history = problem.solve(wrap, first_step=0.02 / wrap, max_step=0.05 / wrap, on_step=switch)
x, N = problem.axial_force()
wound = (x[:, 0] > 0.1 * rho * wrap) & (x[:, 0] < 0.6 * rho * wrap)
if MPI.COMM_WORLD.rank == 0:
    print(f"{len(history)} steps, {sum(s.iterations for s in history)} Newton iterations")
    print(f"T - N = {pull - N[wound].mean():.4f} N against Eq. 2.6 {eq_2_6:.4f} N")
