"""The hybrid's coiling as a phase of the one runner: ``[model] kind = "hybrid"`` in a run.

:class:`HybridCoilingPhase` coils with :class:`~tapecoil.phases.hybrid_coiling.HybridCoiling`
(a shell window that follows the lift-off, beams before and after it) and keeps a full shell
of the same tape (a :class:`~tapecoil.phases.coiling.CoilingProblem`) in the hybrid's
configuration: after every converged step the hybrid's state is carried into it
(:meth:`HybridCoiling.carry_into`), so that the snapshots, the ParaView series and the
geometric measures of a step (the deployed fraction, the penetration) are the whole tape's, as
in the shell's coiling. The energies and forces of the history rows are the hybrid's own.

At the end the full shell, placed in the hybrid's configuration, is solved once at the final
hub angle ("settled"): the beams' sections are rigid (the coil's flattened strip without its
edges' lift, the arc without its flattening under load), and the shell's interpolation of the
placed turns strains it (on the coarse mesh an element spans about a radian of the hub). That
equilibrium is the stowed state: its checkpoint, the coil's measures of the summary (the same
names as the shell's) and the deployment from it are the full shell's. The summary's
``measures["hybrid"]`` keeps the hybrid's own energy and what settling changed.

Its checkpoints (stowed/) are the full shell's, in the hybrid's configuration (or settled, at
the end), with the hybrid's own state beside it (``tables.npz``: the window's and the beams'
fields cell by cell, :meth:`HybridProblem.state_tables`, and in the meta where the window is
and the step it was taking): a stopped coiling goes on from its last checkpoint as if never
stopped, and a completed one gives its hybrid's coil to the deployment without coiling again.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.core.dofs import global_size
from tapecoil.core.stepping import ContinuationError
from tapecoil.measures.coiling import coil_measures
from tapecoil.measures.deployment import lift_off
from tapecoil.measures.payout import (
    OUTER_TURN_COLUMNS,
    eq_4_5,
    steady_torque,
    tension_law,
    tension_law_with_edges,
)
from tapecoil.models.nodes import Nodes
from tapecoil.phases.coiling import CoilingProblem, write_checkpoint
from tapecoil.phases.coiling_run import HubTurningPhase, write_coiled_cells
from tapecoil.phases.hybrid_coiling import HybridCoiling, WindowSettings
from tapecoil.phases.model_tag import HYBRID, KEY, by_hybrid
from tapecoil.phases.runner import LOG, run_phase
from tapecoil.phases.stepped import clock_origin, last_wall_time

# solves of the full shell from the hybrid's coiled state before the coiling stops
SETTLE_ATTEMPTS = 2

__all__ = ["HybridCoilingPhase", "run_hybrid_coiling", "settle"]


class HybridCoilingPhase(HubTurningPhase):
    """The hybrid's coiling to ``coiling.hub_angle`` (see the module), the full shell settled at
    the end. ``restart``: the restart state of a checkpoint (its history, windows and settling),
    whose full shell is ``model`` and whose hybrid is ``coiling`` (restored from it, or None
    when the checkpoint has none); ``completed``: that coiling had ended, and nothing is computed."""

    name, checkpoint_name = "coiling", "stowed"

    def __init__(
        self,
        config: Config,
        comm=MPI.COMM_WORLD,
        model: CoilingProblem | None = None,
        restart=None,
        stop=None,
        coiling: HybridCoiling | None = None,
        completed: bool = False,
    ):
        super().__init__(model or CoilingProblem(config, comm))
        self.config, self.comm, self.stop = config, comm, stop
        self.target = config.coiling.hub_angle
        self.settling: dict = dict(restart["settling"]) if restart else {}
        self.windows: list = [tuple(w) for w in restart["windows"]] if restart else []
        self.history = list(restart["history"]) if restart else []
        self.completed = completed
        self.coiling = coiling
        self._cells = None
        self._t0 = clock_origin(last_wall_time(self.history))

    def restart_state(self) -> dict:
        return {
            KEY: HYBRID,
            "history": self.history,
            "settling": self.settling,
            "windows": self.windows,
            "coiling": None if self.coiling is None else self.coiling.restart_state(),
        }

    def write_checkpoint(self, path: Path, meta: dict) -> None:
        """The full shell's checkpoint with the hybrid's tables beside it (collective)."""
        tables = None if self.coiling is None else self.coiling.hybrid.state_tables()
        write_checkpoint(self.model, path, meta, tables)

    def progress(self, row: dict) -> tuple[float, float, int, str, bool]:
        window = f" window {row['window_start']:.3f}-{row['window_end']:.3f} m"
        return row["hub_angle"], row["step"], row["newton_iterations"], f" {row['phase']}{window}", True

    # -- the run ------------------------------------------------------------------------------
    def advance(self) -> None:
        if self.coiling is None:
            self._t0 = time.perf_counter()
            self.coiling = HybridCoiling(
                self.config, self.comm, window=WindowSettings.from_config(self.config.model)
            )
            flattening = self.coiling.flatten()
            self._step("flatten", 0.0, 0.0, sum(int(r.iterations) for r in flattening))
        self.coiling.coil(
            self.target, on_step=lambda r: self._step("coil", r.hub_angle, r.step, r.iterations)
        )
        self.settle()
        self.completed = True

    def _step(self, phase: str, angle: float, step: float, iterations: int) -> None:
        """A converged step: the full shell put in the hybrid's configuration, the row recorded."""
        coiling = self.coiling
        coiling.carry_into(self.model)
        self.windows = [tuple(w) for w in coiling.moves]
        row = self._row(phase, angle, step, iterations)
        self.history.append(row)
        if self.on_row is not None:
            self.on_row(row)
        if self.stop is not None:
            self.stop.check(self.comm)

    def _row(self, phase: str, angle: float, step: float, iterations: int) -> dict:
        """What the step measured: the hybrid's energy and forces, the whole tape's geometry (the
        full shell in the hybrid's configuration) with the shell's coiling's column names."""
        coiling, config = self.coiling, self.config
        pull = coiling.pull
        geometry = coiling.coil_geometry()
        lam = lift_off(self.model.tape)["lambda"]
        start, end = coiling.hybrid.shell.surface.xi_range[0]
        turning = phase != "flatten"
        outer = coiling.outer_turn_tension() if turning else None
        if outer is None:
            outer_columns = dict.fromkeys(OUTER_TURN_COLUMNS, "")
        else:
            rho = outer["outer_turn_radius"]
            outer_columns = {
                "station_winding": outer["station_winding"],
                "outer_turn_radius": rho,
                "coiling_tension_outer": outer["coiling_tension_outer"],
                "eq_2_6_outer": float(tension_law(rho, config)),
                "eq_2_6_edges_outer": tension_law_with_edges(rho, config),
                "eq_4_5": float(eq_4_5(lam, config)),
                "steady_torque": steady_torque(rho, pull, config),
            }
        root_tension = coiling.root_tension()
        return {
            "phase": phase,
            "hub_angle": angle,
            "step": step,
            "newton_iterations": iterations,
            "tension": pull,
            "root_tension": root_tension,
            "coiling_tension": pull - root_tension,
            "hub_torque_reaction": coiling.hub_torque() if turning else "",
            "strain_energy": coiling.strain_energy(),
            "max_penetration": self.model.tape.max_penetration(),
            "coiled_length": geometry["coiled_length"],
            "outer_radius": geometry["outer_radius"],
            "lambda": lam,
            "window_start": start,
            "window_end": end,
            "dofs": coiling.dofs(),
            **outer_columns,
            "wall_time": time.perf_counter() - self._t0,
        }

    def settle(self) -> None:
        """The full shell settled at the final hub angle (:func:`settle`), with the hybrid's
        energy beside its own (collective)."""
        self.settling = {
            "strain_energy_hybrid": self.coiling.strain_energy(),
            **settle(self.model, self.coiling.angle),
        }
        LOG.info(
            "the full shell settled from the hybrid's coil in %d Newton iterations: strain energy "
            "%.6g J (hybrid %.6g J), displaced by at most %.3g m",
            self.settling["newton_iterations"],
            self.settling["strain_energy_settled"],
            self.settling["strain_energy_hybrid"],
            self.settling["largest_displacement"],
        )

    # -- the results ----------------------------------------------------------------------------
    def finish(self, directory: Path) -> None:
        """coiled_cells.csv, as the shell's coiling writes it."""
        self._cells = write_coiled_cells(self.model, directory)

    def run_figures(self, steps: int, t_start: float) -> dict:
        """The shell's coiling's run figures, the DOFs the hybrid's (at its largest), with the
        hybrid's own: its model, its windows and the settling's solve."""
        history, res = self.history, self.model.strip.resolution
        return {
            KEY: HYBRID,
            "ranks": self.comm.size,
            "dofs": max((int(r["dofs"]) for r in history), default=0),
            "full_shell_dofs": global_size(self.model.model.W),
            "mesh": f"{res.along} x {res.across}",
            "predictor": self.model.predictor,
            "penalty": self.model.penalty,
            "steps": steps,
            "newton_iterations": int(sum(int(r["newton_iterations"]) for r in history)),
            "max_penetration": max((float(r["max_penetration"]) for r in history), default=0.0),
            "wall_time": history[-1]["wall_time"] if history else 0.0,
            "process_wall_time": time.perf_counter() - t_start,
            "windows": [list(w) for w in self.windows],
            "settling": self.settling,
            "account": settling_account(self.settling),
        }

    def summary(self, interrupted, t_start: float) -> dict:
        """The coil's measures of the settled full shell, named as the shell's coiling's, and the
        hybrid's own beside them."""
        measures = coil_measures(self.model.tape, self._cells)
        hybrid = {"strain_energy": self.settling.get("strain_energy_hybrid")}
        last = next((r for r in reversed(self.history) if r["phase"] == "coil"), None)
        if last is not None:
            hybrid.update(coiled_length=last["coiled_length"], outer_radius=last["outer_radius"])
        measures["hybrid"] = hybrid
        return self.coiling_summary(interrupted, t_start, measures)


def settle(model: CoilingProblem, angle: float) -> dict:
    """Solve the full shell of ``model``, put in a hybrid's configuration at the hub angle
    ``angle`` [rad], once there: its equilibrium. Returns the solve's Newton iterations and
    wall time [s], the strain energy [J] before and after, and the largest displacement [m]
    and director angle change [rad] it made; on failure the state is put back and
    :class:`~tapecoil.core.stepping.ContinuationError` raised (collective)."""
    carried_energy = model.tape.energies()["strain"]
    before = model.model.q.x.array.copy()
    model.viscosity.value = 0.0
    started = time.perf_counter()
    # a second attempt from the carried state, as the steps' cut-backs retry: the turns' real
    # contact then forgets the partners it kept and starts from the closest cells (a settling
    # whose first linear solve failed has settled when its carried state was read back from
    # the checkpoint and solved afresh)
    attempts = 0
    while True:
        attempts += 1
        result = model.solver.solve()
        if result.converged:
            break
        model.model.q.x.array[:] = before
        model.model.q.x.scatter_forward()
        if attempts < SETTLE_ATTEMPTS:
            continue
        raise ContinuationError(
            f"the full shell did not settle from the hybrid's coiled state at {angle:.6g} rad "
            f"(SNES {result.reason_name} after {result.iterations} iterations, {SETTLE_ATTEMPTS} "
            "attempts); the stowed checkpoint holds the hybrid's configuration, not an "
            "equilibrium of the full shell",
            angle,
        )
    model.update(angle)
    nodes = Nodes(model.model)
    change = model.model.q.x.array - before
    moved = float(np.linalg.norm(change[nodes.u_dofs], axis=1).max(initial=0.0))
    turned = float(np.abs(change[nodes.theta_dofs]).max(initial=0.0))
    comm = model.comm
    return {
        "newton_iterations": int(result.iterations),
        "attempts": attempts,
        "wall_time": time.perf_counter() - started,
        "strain_energy_carried": carried_energy,
        "strain_energy_settled": model.tape.energies()["strain"],
        "largest_displacement": comm.allreduce(moved, op=MPI.MAX),
        "largest_director_turn": comm.allreduce(turned, op=MPI.MAX),
    }


def run_hybrid_coiling(
    config: Config,
    directory: str | Path,
    comm=MPI.COMM_WORLD,
    resume: str | Path | None = None,
    progress: bool = True,
    stop=None,
) -> tuple[dict, CoilingProblem, HybridCoiling | None]:
    """Coil with the hybrid into ``directory`` (the files of
    :func:`~tapecoil.phases.coiling_run.run_coiling`); returns the phase summary, the full
    shell's settled :class:`CoilingProblem` and the coiled :class:`HybridCoiling` (the hybrid's own
    state, which its deployment starts from; None when a completed coiling's checkpoint does not
    hold it). ``resume``: a checkpoint of a hybrid coiling to go on from as if never stopped (a
    completed one's summary again, nothing computed); one without the hybrid's state (another
    model's, or an older one's) is not continued, and the coiling starts again."""
    from tapecoil.core.checkpoint import read_meta, read_tables
    from tapecoil.phases.coiling import check_free_end_room, read_checkpoint

    check_free_end_room(config)
    t_start = time.perf_counter()
    if resume is not None:
        meta = read_meta(resume)
        restart = meta.get("run") or {}
        tables = read_tables(resume)
        ours = by_hybrid(restart)
        resumable = ours and tables is not None and restart.get("coiling") is not None
        if resumable or (ours and meta.get("completed")):
            model, _ = read_checkpoint(resume, config, comm)
            coiling = None
            if resumable:
                coiling = HybridCoiling(
                    config,
                    comm,
                    window=WindowSettings.from_config(config.model),
                    restart=restart["coiling"],
                    tables=tables,
                )
            if meta.get("completed"):
                LOG.info("hybrid coiling: completed in %s at %.6g rad", resume, model.root.angle)
                phase = HybridCoilingPhase(config, comm, model, restart, coiling=coiling, completed=True)
                return phase.summary(None, t_start), model, coiling
            LOG.info("hybrid coiling resumed from %s at %.6g rad", resume, coiling.angle)
            phase = HybridCoilingPhase(config, comm, model, restart, stop, coiling=coiling)
            summary = run_phase(phase, directory, config, comm, model.model, restart, progress, t_start)
            return summary, phase.model, phase.coiling
        LOG.warning("hybrid coiling: %s holds no hybrid state to go on from; coiling again", resume)
    phase = HybridCoilingPhase(config, comm, stop=stop)
    res = phase.model.strip.resolution
    LOG.info(
        "coiling with the hybrid: window %g m ahead of the lift-off and %g m behind it, mesh %d x %d, "
        "to %g rad on %d rank(s)",
        config.model.window_ahead,
        config.model.window_behind,
        res.along,
        res.across,
        phase.target,
        comm.size,
    )
    summary = run_phase(phase, directory, config, comm, phase.model.model, None, progress, t_start)
    return summary, phase.model, phase.coiling


def coil_again(config: Config, comm=MPI.COMM_WORLD) -> HybridCoiling:
    """The hybrid's coiling of ``config`` computed again, without files: the hybrid's own
    coiled state, which a checkpoint of the full shell does not hold (for a deployment by the
    hybrid after a resumed coiling)."""
    coiling = HybridCoiling(config, comm)  # the window of config.model
    coiling.flatten()
    coiling.coil(config.coiling.hub_angle)
    return coiling


def settling_account(settling: dict) -> str | None:
    """How the hybrid's coil became the full shell's stowed state, for the report (None before
    the settling)."""
    if not settling:
        return None
    return (
        "Coiled by the shell-beam hybrid (its DOFs above at their most), whose coiled "
        "configuration was carried into the full shell and settled there in "
        f"{settling['newton_iterations']} Newton iterations"
        f"{' (its second attempt)' if settling.get('attempts', 1) > 1 else ''}: strain energy "
        f"{settling['strain_energy_hybrid']:.6g} J in the hybrid, "
        f"{settling['strain_energy_settled']:.6g} J settled, the nodes moved by at most "
        f"{1e3 * settling['largest_displacement']:.3g} mm. The stowed state and the coil's "
        "measures are the full shell's."
    )
