"""Folds seeded with temporary cylinders, as Wilson et al. (2020) seed them (docs/notes/regimes.md,
"Seeded folds"): load-stepped, the wrap over them stalls; taken through in time, it passes.

The wrapping study's wrap (``tapecoil.phases.wrapping``) with SEEDS rigid cylinders fixed to the
hub at winding angles spread evenly over the wrap, of radius R, standing STANDOFF R off the hub:
the tape is wound over them so that beside each one it leaves the hub and runs straight with its
section unflattened, to be pressed flat onto the hub by the pull once the cylinders are gone,
which is the mechanism of Eq. 2.9.

Load-stepped (the default) the script prints each converged step of the wrap and where it
stopped. With ``--dynamic`` the protocol is taken through its snaps in time
(``tapecoil.phases.driven``): the hub turned over the seeds at a tape speed of ``--speed``, the
seeds withdrawn over ``--withdraw-time`` with the end held, the end pulled at ``--pull-speed``
until the centre line conforms over 305 degrees within 3 h. It prints the force then (the
required tension), its mean and spread over the last ``--average`` seconds (the force carries the
motion's oscillation), Eq. 2.9, the folds seen and the cost.

    tools/env.sh run env PYTHONPATH=solver python3 tools/seeded_wrap_study.py \
        [RATIO SEEDS STANDOFF WRAP_PULL FREE_LENGTH ELEMENT_SIZE ACROSS] [--dynamic ...]

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


def quasi_static_wrap(model, study, comm) -> str:
    """The wrapping study's load-stepped wrap over the seeds; how it ended."""
    from tapecoil.core.stepping import ContinuationError
    from tapecoil.phases import coiling_run

    def show(row: dict) -> None:
        if comm.rank == 0 and row["phase"] == "coil":
            print(
                f"hub angle {row['hub_angle']:.5f} rad: root tension {row['root_tension']:.4f} N, "
                f"{row['newton_iterations']} Newton iterations, {row['wall_time']:.0f} s",
                flush=True,
            )

    run = coiling_run.CoilingRun(model, on_step=show, max_step=study.wrap_step)
    try:
        run.flatten()
        run.coil(model.config.coiling.hub_angle)
        return "the wrap is complete"
    except ContinuationError as err:
        return f"the wrap stopped: {err}"


def dynamic_wrap(model, seeds, study, options, comm) -> dict:
    """Wilson et al.'s protocol taken through its snaps in time (:mod:`tapecoil.phases.driven`):
    the hub turned over the seeds at the tape speed ``options.speed``, the seeds withdrawn over
    ``options.withdraw_time`` with the end held, the end pulled at ``options.pull_speed`` until the
    centre line conforms. Returns the readings."""
    import time

    import numpy as np

    from tapecoil import theory
    from tapecoil.core.dofs import global_size
    from tapecoil.core.smoothing import smoothstep
    from tapecoil.core.stepping import ContinuationError
    from tapecoil.phases import coiling_run
    from tapecoil.phases.driven import DrivenMotion
    from tapecoil.phases.wrapping import EndDisplacement, wrap_reading

    cfg = model.config
    tp, r_c = cfg.tape, cfg.hub.radius
    rho = r_c + tp.h / 2
    wrap = cfg.coiling.hub_angle
    eq_2_9 = theory.coiling_tension_tension_dominated(cfg.wall.bending, tp.alpha, tp.R, rho)
    t0 = time.perf_counter()
    coiling_run.CoilingRun(model).flatten()

    # the hub's angle: accelerated over `ramp` to the speed omega, then turned steadily
    omega, ramp = options.speed / rho, 0.02

    def hub_angle(t: float) -> float:
        return omega * t * t / (2 * ramp) if t < ramp else omega * (t - ramp / 2)

    motion = DrivenMotion(model, rho_inf=options.rho_inf, prefix="wrap_")
    duration = wrap / omega + ramp / 2
    motion.run(duration, lambda t: model.set_hub_angle(min(hub_angle(t), wrap)), options.dt)
    model.set_hub_angle(wrap)
    wrap_steps, wrap_iterations = motion.steps, motion.iterations
    motion.destroy()
    if comm.rank == 0:
        print(
            f"wrapped in {wrap_steps} steps, {wrap_iterations} Newton iterations, "
            f"{time.perf_counter() - t0:.0f} s"
        )

    end = EndDisplacement(model)  # the end held where the wrap left it; the pull is off
    motion = DrivenMotion(model, bcs=(end.bc,), rho_inf=options.rho_inf, prefix="pull_")
    history = []

    def read(stage: str, d: float) -> dict:
        reading = wrap_reading(model, wrap, study.tolerance)
        row = {
            "stage": stage,
            "time": motion.time,
            "end_displacement": d,
            "force": model.edge_forces()["tension"],
            "kinetic_energy": motion.kinetic_energy(),
            **reading,
        }
        history.append(row)
        if comm.rank == 0 and len(history) % 10 == 0:
            print(
                f"{stage} t = {row['time']:.4f} s, d = {d * 1e3:.3f} mm: force {row['force']:.3f} N, "
                f"conforms over {row['conforming_wrap_deg']:.1f} deg, {row['folds']} folds, "
                f"{time.perf_counter() - t0:.0f} s",
                flush=True,
            )
        return row

    withdraw = options.withdraw_time
    motion.run(
        withdraw,
        lambda t: seeds.withdraw(0.999 * float(smoothstep(t / withdraw))),
        options.dt,
        on_step=lambda step: read("withdraw", 0.0),
    )

    def end_at(t: float) -> float:
        s = t - withdraw
        return options.pull_speed * (s * s / (2 * ramp) if s < ramp else s - ramp / 2)

    class Conformed(Exception):
        pass

    def pulled(step) -> None:
        if read("pull", end_at(step.load))["conforming_wrap_deg"] >= study.conform_angle:
            raise Conformed

    required, message = None, ""
    span = (options.max_pull + options.pull_speed * ramp / 2) / options.pull_speed
    try:
        motion.run(span, lambda t: end.set(end_at(t)), options.dt, on_step=pulled)
        message = f"no conformity within {options.max_pull * 1e3:g} mm of pull"
    except Conformed:
        required = history[-1]["force"]
    except ContinuationError as err:
        message = f"stopped: {err}"
    # the force oscillates with the motion: its mean over the last `average` seconds of the pull
    recent = [
        r["force"] for r in history if r["stage"] == "pull" and r["time"] >= motion.time - options.average
    ]
    most = max(history, key=lambda r: r["folds"])
    radii = [r for row in history for r in row["fold_radii"]]
    return {
        "required_tension": required,
        "mean_force": float(np.mean(recent)) if recent else None,
        "force_spread": (float(min(recent)), float(max(recent))) if recent else None,
        "eq_2_9": eq_2_9,
        "max_folds": most["folds"],
        "fold_radius_range": (min(radii) / tp.R, max(radii) / tp.R) if radii else None,
        "pull": history[-1]["end_displacement"],
        "wrap_steps": wrap_steps,
        "wrap_newton_iterations": wrap_iterations,
        "steps": motion.steps,
        "newton_iterations": motion.iterations,
        "dofs": global_size(model.model.W),
        "wall_time": time.perf_counter() - t0,
        "message": message,
    }


def main(argv: list[str]) -> None:
    import argparse

    from mpi4py import MPI

    from tapecoil.config import config_from_dict
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.tape_on_hub import TapeOnHub
    from tapecoil.phases.wrapping import WrapStudy, wrap_case

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "values", nargs="*", help="RATIO SEEDS STANDOFF WRAP_PULL FREE_LENGTH ELEMENT_SIZE ACROSS"
    )
    parser.add_argument("--dynamic", action="store_true", help="wrap, withdraw and pull in time")
    parser.add_argument("--speed", type=float, default=0.5, help="tape speed of the wrap [m/s]")
    parser.add_argument("--withdraw-time", type=float, default=0.05, help="time the seeds take to go [s]")
    parser.add_argument("--pull-speed", type=float, default=0.05, help="speed of the end's pull [m/s]")
    parser.add_argument("--max-pull", type=float, default=0.03, help="how far the end may be pulled [m]")
    parser.add_argument("--dt", type=float, default=2e-4, help="largest time step [s]")
    parser.add_argument("--rho-inf", type=float, default=0.3, help="generalized-alpha spectral radius")
    parser.add_argument("--average", type=float, default=0.005, help="the force's averaging time [s]")
    options = parser.parse_args(argv)
    defaults = [4.3, 2, 0.5, 0.2, 0.3, 0.008, 4]
    given = options.values + [str(d) for d in defaults][len(options.values) :]
    ratio, seeds, standoff, pull, free, size, across = [
        type(d)(a) for d, a in zip(defaults, given, strict=True)
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
    model = CoilingProblem(case, comm, tape=tape, obstacles=(bodies,))
    if comm.rank == 0:
        print(
            f"r_c/R = {ratio}, {seeds} seeds at {[round(math.degrees(a)) for a in angles]} deg standing "
            f"{standoff} R off, pull {case.coiling.tension:.3f} N, {case.tape.L:.3f} m of tape"
        )
    if not options.dynamic:
        message = quasi_static_wrap(model, study, comm)
        if comm.rank == 0:
            print(message)
        return
    result = dynamic_wrap(model, bodies, study, options, comm)
    if comm.rank == 0:
        for key, value in result.items():
            print(f"{key}: {value}")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
