"""What a move of the hybrid's window costs against a load step (docs/notes/hybrid.md, "Moving the
window"): a 0.5 m cantilever of the benchmark section on the default mesh (9 elements across,
4 mm along), its root clamped on the beam, a shell window of 0.148 m from 0.048 m, under a tip
force stepped by 0.05 N; the window moved on by 20 mm MOVES times, each move followed by one
load step. Prints, per move, the time to build the moved hybrid (meshes, spaces, forms from the
cache, ties), to carry the state over, and of the load step after it (its solver's set-up
included), with its Newton iterations; then what the ties' derivatives in the beam ends'
dofs cost per evaluation (the gradient in each residual, the Hessian and the mixed derivatives in
each Jacobian).

    tools/env.sh run [mpirun -n 2] env PYTHONPATH=solver python3 tools/hybrid_move_cost.py [MOVES]
"""

import sys
import time

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.models.window import carry_over
from tapecoil.verification.hybrid import tape_hybrid

LENGTH, ELEMENT, WINDOW, START, SHIFT, FORCE_STEP = 0.5, 0.004, 0.148, 0.048, 0.02, 0.05
REPEAT = 50  # evaluations of the ties' derivatives timed
moves = int(sys.argv[1]) if len(sys.argv) > 1 else 3


def build(start, name):
    hybrid, tip = tape_hybrid(Config(), 9, ELEMENT, LENGTH, WINDOW, start=start, name=name)
    hybrid.beam.clamp((0.0, 0.0, tip[2]))
    hybrid.beam.end_load(tip, force=(0.0, 0.0, 1.0))
    return hybrid


def step(hybrid):
    target = hybrid.beam.committed_load + FORCE_STEP
    span = target - hybrid.beam.committed_load
    t0 = time.perf_counter()
    hybrid.solve(target, first_step=span, max_step=span)
    return time.perf_counter() - t0, hybrid.history[-1].iterations


def report(text):
    if MPI.COMM_WORLD.rank == 0:
        print(text, flush=True)


t0 = time.perf_counter()
old = build(START, "move0")
report(f"first hybrid: built in {time.perf_counter() - t0:.2f} s; step %.2f s (%d iterations)" % step(old))
for k in range(1, moves + 1):
    t0 = time.perf_counter()
    new = build(START + k * SHIFT, f"move{k}")
    built = time.perf_counter() - t0
    t0 = time.perf_counter()
    carry_over(old, new)
    carried = time.perf_counter() - t0
    wall, iterations = step(new)
    report(
        f"move {k}: built in {built:.2f} s, carried over in {carried:.3f} s; "
        f"the step after it {wall:.2f} s ({iterations} iterations)"
    )
    old = new

# what the ties' derivatives in the beam ends' dofs cost in each Jacobian and residual
coupling = old.coupling
costs = []
for derivative in (coupling.gradient, coupling.hessian, coupling.mixed_vectors):
    derivative()
    t0 = time.perf_counter()
    for _ in range(REPEAT):
        derivative()
    costs.append(1e3 * (time.perf_counter() - t0) / REPEAT)
gradient, hessian, mixed = costs
report(
    f"the ties' derivatives: gradient {gradient:.2f} ms, Hessian {hessian:.2f} ms, "
    f"mixed {mixed:.2f} ms per evaluation"
)
