"""``hybrid-vibration``: the shell-beam hybrid in time (:mod:`tapecoil.phases.hybrid_motion`).

The cantilever of ``hybrid-cantilever`` (the benchmark tape's section, 0.3 m, clamped at the
root; shell over its first 0.1 m, the arc-section beam beyond) is bent by the same small tip
force and let go: it swings in the plane of symmetry. Side by side, the same with shell over all
but its last element (the full shell of ``hybrid-cantilever``, the same end condition). The
predictions:

- the hybrid's period between zero crossings of the tip within 0.1 % of the full shell's (the
  two models' static stiffness agree to 0.3 %, which moves the period by half that);
- both within 1.5 % of Euler-Bernoulli's first mode, 2 pi / (1.8751^2 sqrt(EI / (rho_l L^4)))
  with the arc's EI: beam theory is 0.8 % stiffer than the shell on the coarse mesh
  (``hybrid-cantilever``), so the shell's period is 0.4 % longer than its own, and the
  trapezoidal rule at PER_PERIOD steps per period lengthens it by (omega dt)^2 / 12 = 0.2 %
  (measured 0.9 % on the coarse mesh).

The amplitude is reported, not checked: the ties' penalty is taken at each step's end, as an
implicit Euler step would, and takes a little energy out of the motion.
"""

from __future__ import annotations

import math
import time

import numpy as np
from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import Config
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.models.beam_section import BeamSection
from tapecoil.verification.checks import CaseResult, Check
from tapecoil.verification.hybrid import CANTILEVER_LENGTH, WINDOW, _tip_force, cantilever_tip_deflection

PER_PERIOD = 40  # steps per Euler-Bernoulli period
PERIODS = 2.5  # the motion followed: four zero crossings


def cantilever_period(EI: float, line_density: float, length: float) -> float:
    """Euler-Bernoulli's first period [s] of a cantilever: 2 pi / (1.8751^2 sqrt(EI / (rho_A
    L^4))), EI [N m^2], rho_A [kg/m], L [m]."""
    return 2 * math.pi / (1.875104**2 * math.sqrt(EI / (line_density * length**4)))


def euler_bernoulli_period(config: Config) -> float:
    """The first period [s] of the tape's cantilever by Euler-Bernoulli, the arc's EI."""
    tp = config.tape
    return cantilever_period(
        tp.E * theory.arc_second_moment(tp.R, tp.alpha, tp.h), tp.rho_l, CANTILEVER_LENGTH
    )


def crossing_period(times: np.ndarray, values: np.ndarray) -> float | None:
    """Twice the mean time [s] between the zero crossings of ``values`` at ``times`` (linear
    between the samples); None before two crossings."""
    crossings = [
        times[i] - values[i] * (times[i + 1] - times[i]) / (values[i + 1] - values[i])
        for i in range(len(values) - 1)
        if values[i] * values[i + 1] < 0
    ]
    return 2 * float(np.mean(np.diff(crossings))) if len(crossings) > 1 else None


def swing(
    config: Config,
    resolution: MeshResolution,
    window: float,
    per_period: int = PER_PERIOD,
    periods: float = PERIODS,
    rho_inf: float = 1.0,
    comm=MPI.COMM_WORLD,
) -> dict:
    """The tape cantilever with ``window`` [m] of shell at its root, let go from the static
    deflection of the case's tip force: the times [s] and tip deflections [m] of ``per_period``
    steps per Euler-Bernoulli period over ``periods`` of them, the static deflection, the
    period between zero crossings [s] (None before two of them), steps, Newton iterations and
    wall time [s]."""
    from tapecoil.phases.hybrid_motion import HybridMotion

    tp = config.tape
    static, hybrid, _ = cantilever_tip_deflection(config, resolution, window, _tip_force(config), comm=comm)
    tip = (CANTILEVER_LENGTH, 0.0, hybrid.ties["xi1_max"].end[2])
    arc = BeamSection.circular_arc(tp.R, tp.alpha, tp.h, tp.E, tp.nu)
    # the section's mass moments of inertia per unit length: density times its second moments
    rotary = tp.density * np.array([arc.EI2 + arc.EI3, arc.EI2, arc.EI3]) / tp.E
    motion = HybridMotion(hybrid, tp, tp.rho_l, rotary, rho_inf=rho_inf, settings=config.solver)
    motion.set_load(0.0)  # let go
    dt = euler_bernoulli_period(config) / per_period
    times, tips, iterations = [], [], 0
    t0 = time.perf_counter()
    try:
        for _ in range(round(periods * per_period)):
            result = motion.step(dt)
            if not result.converged:
                raise RuntimeError(f"hybrid-vibration: a step did not converge at t = {motion.time:.6g} s")
            iterations += result.iterations
            times.append(motion.time)
            tips.append(float(hybrid.beam.position(tip)[2] - tip[2]))
    finally:
        motion.destroy()
    times, tips = np.array(times), np.array(tips)
    return {
        "times": times,
        "tips": tips,
        "static": static,
        "period": crossing_period(times, tips),
        "amplitude_last_period": float(np.abs(tips[-per_period:]).max()),
        "steps": len(times),
        "newton_iterations": iterations,
        "wall_time": time.perf_counter() - t0,
    }


def hybrid_vibration(config: Config, resolution: MeshResolution, comm=MPI.COMM_WORLD) -> CaseResult:
    """The hybrid cantilever's first period against the full shell's and Euler-Bernoulli's."""
    element = CANTILEVER_LENGTH / resolution.along
    hybrid = swing(config, resolution, WINDOW, comm=comm)
    full = swing(config, resolution, CANTILEVER_LENGTH - element, comm=comm)
    reference = euler_bernoulli_period(config)
    keep = ("static", "period", "amplitude_last_period", "steps", "newton_iterations", "wall_time")
    return CaseResult(
        "hybrid-vibration",
        [
            Check("first period, hybrid / full shell", hybrid["period"] / full["period"], 1.0, 1e-3),
            Check("first period, hybrid / Euler-Bernoulli", hybrid["period"] / reference, 1.0, 0.015),
            Check("first period, full shell / Euler-Bernoulli", full["period"] / reference, 1.0, 0.015),
        ],
        {
            "mesh": f"{resolution.across} across, elements {element * 1e3:.3g} mm long",
            "steps_per_period": PER_PERIOD,
            "euler_bernoulli_period": reference,
            "hybrid": {k: hybrid[k] for k in keep},
            "full_shell": {k: full[k] for k in keep},
        },
    )
