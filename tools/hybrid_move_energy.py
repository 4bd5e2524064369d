"""Where the strain energy goes at the hybrid's window moves in its deployment: the benchmark
tape coiled by the hybrid to HUB_ANGLE [rad] (default 36) and deployed by it to lambda = 0.9,
and at every window move the strain energy of the tape's stretches before and after the move
(the settling of the placed sections included), each integrated over its own stretch of the
material coordinate with the solve's own quadrature:

- ``placed``: the coil that the move turns from flattened beam into shell, with the old window's
  first element, which the settling frees too;
- ``withdrawn``: the tape beyond the new window's end, turned from shell into arc beam;
- ``kept``: the rest, shell or beam on both sides of the move (untouched by it, a consistency
  check: its energy passes to round-off).

Printed per move: the time, the window before and after, and each stretch's energy before and
its change [J]; the energy of the ties and of contact are left out (docs/notes/hybrid.md, "The
deployment by the hybrid").

    tools/env.sh run [mpirun -n 2] env PYTHONPATH=solver python3 tools/hybrid_move_energy.py [--mesh coarse]
"""

import argparse
import dataclasses

import dolfinx
import ufl
from mpi4py import MPI

from tapecoil.config import load_config
from tapecoil.core.dofs import global_scalar
from tapecoil.phases.hybrid_coiling import HybridCoiling
from tapecoil.phases.hybrid_deployment import HybridDeployment

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("hub_angle", nargs="?", type=float, default=36.0, help="coiling's hub angle [rad]")
parser.add_argument("--mesh", default="coarse", choices=("coarse", "default"))
parser.add_argument("--lambda-end", type=float, default=0.9)
args = parser.parse_args()
comm = MPI.COMM_WORLD
config = load_config()
config = dataclasses.replace(
    config,
    mesh=dataclasses.replace(config.mesh, preset=args.mesh),
    coiling=dataclasses.replace(config.coiling, hub_angle=args.hub_angle),
    deployment=dataclasses.replace(config.deployment, lambda_end=args.lambda_end),
)


class StretchEnergy:
    """The strain energy of a hybrid's shell and beam between two material coordinates [m]
    (collective): the shell's with its solve's quadrature, the beam's likewise."""

    def __init__(self, hybrid):
        shell, beam = hybrid.shell.model, hybrid.beam.model
        self.bounds = [dolfinx.fem.Constant(m, (0.0, 0.0)) for m in (shell.mesh, beam.mesh)]
        s_shell, s_beam = shell.xi[0], ufl.SpatialCoordinate(beam.mesh)[0]
        self.forms = []
        shell_weight = self._inside(s_shell, self.bounds[0])
        self.forms.append(dolfinx.fem.form(sum(shell.energy_forms(shell_weight))))
        beam_weight = self._inside(s_beam, self.bounds[1])
        self.forms.append(dolfinx.fem.form(beam_weight * beam.energy_density * beam.dx))

    @staticmethod
    def _inside(s, bounds):
        return ufl.conditional(ufl.And(ufl.ge(s, bounds[0]), ufl.lt(s, bounds[1])), 1.0, 0.0)

    def __call__(self, start: float, end: float) -> float:
        for bounds in self.bounds:
            bounds.value[:] = (start, end)
        return sum(global_scalar(form, comm) for form in self.forms)


moves = []


def stretches(old_window, new_window, element):
    """(name, start, end) of the stretches a move from ``old_window`` to ``new_window`` makes."""
    (s0, e0), (s1, e1) = old_window, new_window
    tol = 1e-6 * element
    # the settling frees the old window's first element: the one beyond it changes too
    placed = (s1 - tol, s0 + 2 * element - tol)
    withdrawn = (e1 - tol, e0 - tol)
    return {
        "placed": [placed],
        "withdrawn": [withdrawn],
        "kept": [(-1.0, placed[0]), (placed[1], withdrawn[0]), (withdrawn[1], 2 * config.tape.L)],
    }


def read(hybrid, parts):
    energy = StretchEnergy(hybrid)
    return {name: sum(energy(a, b) for a, b in spans) for name, spans in parts.items()}


original_move = HybridDeployment._move


def measured_move(self, start):
    old_window = self.window()
    old = self.hybrid
    element = self.coiling.element
    new_end = start + (old_window[1] - old_window[0])
    parts = stretches(old_window, (start, min(new_end, config.tape.L)), element)
    before = read(old, parts)
    original_move(self, start)
    parts = stretches(old_window, self.window(), element)
    after = read(self.hybrid, parts)
    settled = self.placed_settling[-1]
    fitted = (settled["withdrawn_strain_energy_fitted"], settled["withdrawn_strain_energy_settled"])
    moves.append(
        (self.time, old_window, self.window(), before, after, components(self.hybrid, parts), fitted)
    )


def components(hybrid, parts):
    """The beam's energy in the withdrawn stretch by strain: axial, the two shears, twist and
    the two bendings [J]."""
    beam = hybrid.beam.model
    ((a, b),) = parts["withdrawn"]
    inside = StretchEnergy._inside(ufl.SpatialCoordinate(beam.mesh)[0], (a, b))
    c, bend = beam.section_fields, beam.bending_strain
    terms = [0.5 * c[i] * beam.strain[i] ** 2 for i in range(3)]
    terms += [0.5 * c[3 + i] * bend[i] ** 2 for i in range(3)]
    return [global_scalar(dolfinx.fem.form(inside * t * beam.dx), comm) for t in terms]


HybridDeployment._move = measured_move

coiling = HybridCoiling(config, comm)
coiling.flatten()
coiling.coil(config.coiling.hub_angle)
deployment = HybridDeployment(coiling)
deployment.run()
deployment.destroy()

if comm.rank == 0:
    print(
        f"the benchmark coiled to {args.hub_angle:g} rad and deployed by the hybrid to lambda = "
        f"{args.lambda_end:g} ({args.mesh} mesh, {comm.size} rank(s)): the strain energy [J] of "
        "each stretch before a window move and its change across it (settling included)"
    )
    print(
        "t [ms]   window before -> after [m]        placed: before, change"
        "      withdrawn: before, change      kept: before, change"
    )
    for t, w0, w1, before, after, *_ in moves:
        cells = "  ".join(
            f"{before[k]:.5f} {after[k] - before[k]:+.2e}" for k in ("placed", "withdrawn", "kept")
        )
        print(f"{1e3 * t:7.2f}  {w0[0]:.4f}-{w0[1]:.4f} -> {w1[0]:.4f}-{w1[1]:.4f}  {cells}")
    print(
        "the arc beam's energy in the withdrawn stretch after the move [J]: axial, shear 2, "
        "shear 3, twist, bending 2, bending 3"
    )
    for t, *_, parts, _ in moves:
        print(f"{1e3 * t:7.2f}  " + "  ".join(f"{e:.3e}" for e in parts))
    print("the beam's strain energy [J] with the nodes fitted to the shell, and what settling them took off")
    for t, *_, fitted in moves:
        print(f"{1e3 * t:7.2f}  {fitted[0]:.6f}  {fitted[0] - fitted[1]:.3e}")
