"""Folds seeded with temporary cylinders, as Wilson et al. (2020) seed them: the wrap over
them stalls (docs/regimes.md, "Seeded folds").

The wrapping study's wrap (``tapecoil.phases.wrapping``) with SEEDS rigid cylinders fixed to the
hub at winding angles spread evenly over the wrap, of radius R, standing STANDOFF R off the hub:
the tape is wound over them so that beside each one it leaves the hub and runs straight with its
section unflattened, to be pressed flat onto the hub by the pull once the cylinders are gone,
which is the mechanism of Eq. 2.9. Prints each converged step of the wrap and where it stopped.

    tools/env.sh run env PYTHONPATH=solver python3 tools/seeded_wrap_study.py \
        [RATIO SEEDS STANDOFF WRAP_PULL FREE_LENGTH ELEMENT_SIZE ACROSS]

Defaults: the steel tape of demos/coiling_regimes.toml on r_c/R = 4.3, 2 seeds standing 0.5 R
off, pulled by 0.2 of Eq. 2.9, 0.3 m free, 8 mm elements, 4 across.

Each seed is a rigid cylinder parallel to the hub's axis: its axis sits on the material winding
angle psi_k of the wrap (it comes to the hub's top generator when the hub has turned by psi_k),
at the distance that lets it stand ``standoff`` off the hub's surface. The tape's inner face (the
hub's side) is kept out of it by the hub's penalty and smoothed bracket, g = r_s - |P - c_k|_xz.
"""

from __future__ import annotations

import math

import dolfinx
import numpy as np
import ufl

from tapecoil.core.dofs import global_scalar
from tapecoil.core.smoothing import penetration_ufl
from tapecoil.hub.frame import HubFrame
from tapecoil.models.shell import NaghdiShell


def seed_excess_length(hub_radius: float, seed_radius: float, standoff: float) -> float:
    """The tape length [m] a seed adds to a wrap: the belt path round the hub and one seed, less
    the hub's arc it spans (two tangents and the arc round the seed for the arc of the hub)."""
    a, b = hub_radius, seed_radius
    d = a + standoff - b  # the seed's axis from the hub's
    tangent = math.sqrt(d * d - (a - b) ** 2)
    gamma = math.acos((a - b) / d)  # the tangent points' angle from the line of the axes
    return 2 * tangent + 2 * gamma * (b - a)


class FoldSeeds:
    """Rigid cylinders fixed to the hub at winding angles ``winding_angles`` [rad], of radius
    ``radius`` [m], standing ``standoff`` [m] off the hub's surface, against the tape's inner face
    with the penalty stiffness ``penalty`` [N/m^3] and the hub's ``smoothing`` of the bracket [m]
    (see the module)."""

    def __init__(
        self,
        model: NaghdiShell,
        frame: HubFrame,
        penalty: float,
        winding_angles: tuple[float, ...],
        radius: float,
        standoff: float,
        smoothing: float = 0.0,
    ):
        if not 0 < radius < standoff + frame.radius:
            raise ValueError(f"a seed needs 0 < radius < standoff + hub radius, got {radius}, {standoff}")
        self.frame = frame
        self.winding_angles = tuple(float(a) for a in winding_angles)
        self.radius0 = float(radius)
        self.standoff = float(standoff)
        self.axis_distance = frame.radius + standoff - radius
        mesh = model.mesh
        self.comm = mesh.comm
        self.radius = dolfinx.fem.Constant(mesh, self.radius0)
        self.centres = [dolfinx.fem.Constant(mesh, np.zeros(3)) for _ in self.winding_angles]
        face = model.phi + 0.5 * model.material.h * frame.contact_side * model.d
        k = dolfinx.fem.Constant(mesh, float(penalty))
        energy = 0
        for centre in self.centres:
            rel = face - centre
            gap = self.radius - ufl.sqrt(rel[0] ** 2 + rel[2] ** 2)
            energy = energy + 0.5 * k * penetration_ufl(gap, smoothing) ** 2 * model.jacobian * model.dx
        self.energy = energy
        self._energy_form = dolfinx.fem.form(energy)
        self.turn(0.0)

    def centre_at(self, psi: float, hub_angle: float) -> np.ndarray:
        """The axis point (y = 0) of the seed at winding angle ``psi`` with the hub at
        ``hub_angle`` [m]: on the top generator's ray when the hub has turned by psi."""
        top = self.frame.axis_point + self.axis_distance * np.array([0.0, 0.0, self.frame.sign])
        return self.frame.turn_points(top[:, None], hub_angle - psi)[:, 0]

    def turn(self, hub_angle: float) -> None:
        """Carry the seeds round with the hub to ``hub_angle`` [rad]."""
        self.hub_angle = hub_angle
        for centre, psi in zip(self.centres, self.winding_angles, strict=True):
            centre.value[:] = self.centre_at(psi, hub_angle)

    def withdraw(self, fraction: float) -> None:
        """Shrink the seeds about their axes to (1 - ``fraction``) of their radius."""
        self.radius.value = (1.0 - fraction) * self.radius0

    def contact_energy(self) -> float:
        """The seeds' penalty energy [J] (collective)."""
        return global_scalar(self._energy_form, self.comm)


STEEL = {
    "tape": {"R": 0.0192, "alpha": 1.5, "h": 1.2e-4, "L": 1.0, "E": 210e9, "nu": 0.3, "rho_l": 0.0278208},
    "coiling": {"hub_angle": 5.0},
}


def main(argv: list[str]) -> None:
    from mpi4py import MPI

    from tapecoil.config import config_from_dict
    from tapecoil.core.stepping import ContinuationError
    from tapecoil.phases import coiling_run
    from tapecoil.phases.coiling import CoilingModel
    from tapecoil.phases.tape_on_hub import TapeOnHub
    from tapecoil.phases.wrapping import WrapStudy, wrap_case

    defaults = [4.3, 2, 0.5, 0.2, 0.3, 0.008, 4]
    ratio, seeds, standoff, pull, free, size, across = [
        type(d)(a) for d, a in zip(defaults, argv + [str(d) for d in defaults][len(argv) :], strict=True)
    ]
    comm = MPI.COMM_WORLD
    config = config_from_dict({**STEEL, "hub": {"radius": ratio * STEEL["tape"]["R"]}})
    R, r_c = config.tape.R, config.hub.radius
    study = WrapStudy(wrap_pull=pull, free_length=free, element_size=size, elements_across=across)
    wrap = math.radians(study.wrap_angle)
    case = wrap_case(config, study, seeds * seed_excess_length(r_c, R, standoff * R))
    tape = TapeOnHub(case, comm)
    angles = tuple(wrap * k / (seeds + 1) for k in range(1, seeds + 1))
    bodies = FoldSeeds(tape.model, tape.frame, tape.penalty, angles, R, standoff * R, tape.contact.smoothing)
    model = CoilingModel(case, comm, tape=tape, obstacles=(bodies,))

    def show(row: dict) -> None:
        if comm.rank == 0 and row["phase"] == "coil":
            print(
                f"hub angle {row['hub_angle']:.5f} rad: root tension {row['root_tension']:.4f} N, "
                f"{row['newton_iterations']} Newton iterations, {row['wall_time']:.0f} s",
                flush=True,
            )

    run = coiling_run.CoilingRun(model, on_step=show, max_step=study.wrap_step)
    if comm.rank == 0:
        print(
            f"r_c/R = {ratio}, {seeds} seeds at {[round(math.degrees(a)) for a in angles]} deg standing "
            f"{standoff} R off, pull {case.coiling.tension:.3f} N, {case.tape.L:.3f} m of tape"
        )
    try:
        run.flatten()
        run.coil(wrap)
        message = "the wrap is complete"
    except ContinuationError as err:
        message = f"the wrap stopped: {err}"
    if comm.rank == 0:
        print(message)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
