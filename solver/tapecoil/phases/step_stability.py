"""The stability of a quasi-static run's converged states (``[solver] stability``): the tangent
stiffness's eigenvalues nearest zero with the run's supports, and the count of negative ones
(:mod:`tapecoil.core.stability`), for a history row at every converged step and for the last
state in the summary.

With the hub held (its angle prescribed, the run's own support) the state is stable when none
is negative. With the hub free under the torque that holds it (a dead torque: the hub's angle
then an unknown), the stiffness gains the hub's row and column; its Schur complement over the
tape's dofs is the hub torque's rate along the equilibrium path, dT/dtheta, so the free hub's
state is stable when the held one is and dT/dtheta > 0 (Sylvester's law on the bordered
matrix). The rate is read off the history's hub torques (the root's reactions) over the last
steps: no further solve.

The stiffness is the solver's assembled Jacobian: a part that a solver term applies without a
matrix (the turns' surface contact through its nodal normals, ``contact.turns = 'surface'``)
is left out of it.
"""

from __future__ import annotations

import math
import time

import numpy as np

from tapecoil.core.stability import StabilityAnalysis, held_rows

COLUMNS = ("eigenvalue_nearest_zero", "negative_eigenvalues")


class StepStability:
    """Judges the state a :class:`~tapecoil.core.newton.SNESSolver` holds after each converged
    step: ``count`` eigenvalues nearest zero (SLEPc options under ``<solver prefix>stability_``).
    Collective."""

    def __init__(self, solver, count: int = 3):
        self.solver = solver
        self.analysis = StabilityAnalysis(count, prefix=f"{solver.prefix}stability_")
        self.wall_time = 0.0  # [s], every judgement's
        self.states = 0
        self.last = None

    def judge(self) -> dict:
        """The history columns of the state in place: the eigenvalue nearest zero (the lowest
        when none is negative) and the count of negative eigenvalues."""
        t0 = time.perf_counter()
        self.last = self.analysis.analyse(self.solver.compute_jacobian(), held_rows(self.solver))
        self.wall_time += time.perf_counter() - t0
        self.states += 1
        return {COLUMNS[0]: self.last.eigenvalues[0], COLUMNS[1]: self.last.negative}

    def summary(self, history: list[dict], steps: int = 4) -> dict:
        """The last judged state's stability with the hub held, and with it free under its
        torque: the rate dT/dtheta [N m/rad] of the root reactions' torque over the last
        ``steps`` coiling rows (a least-squares line), and what it makes of the free hub."""
        if self.last is None:
            return {}
        rows = [r for r in history if r.get("phase") == "coil" and r.get("hub_torque_reaction") != ""]
        rows = rows[-steps:]
        rate = math.nan
        if len(rows) >= 2:
            angle = np.array([float(r["hub_angle"]) for r in rows])
            torque = np.array([float(r["hub_torque_reaction"]) for r in rows])
            if np.ptp(angle) > 0:
                rate = float(np.polyfit(angle, torque, 1)[0])
        held = self.last.stable
        return {
            "eigenvalues_hub_held": [float(v) for v in self.last.eigenvalues],
            "negative_eigenvalues_hub_held": int(self.last.negative),
            "stable_hub_held": bool(held),
            "hub_torque_rate": rate,
            "stable_hub_free": bool(held and rate > 0) if math.isfinite(rate) else None,
            "states_judged": self.states,
            "wall_time": self.wall_time,
        }
