"""The hybrid's deployment as a phase of the one runner: the tape coiled by the hybrid deploys
with the hybrid (:class:`~tapecoil.phases.hybrid_deployment.HybridDeployment`), and the run's
files are the full shell's.

The hybrid's state is carried into the full shell (:func:`~tapecoil.models.window.carry_over`)
whenever the runner writes it (the ParaView series and the surface snapshots, every
``output.vtx_every`` steps, and at the end), so that the pictures, the snapshots, the
closest-turns measure and the checkpoint deployed/ are the whole tape's. The history has the
full shell's deployment columns that the hybrid measures (the deployed fraction by the same
definition, the strain, contact and kinetic energies and the energy balance's remainder), with
the window's ends and the hybrid's DOFs, and the root's loads on the hub
(:class:`~tapecoil.phases.root_loads.HybridRootLoads`) with their peaks in the summary.

Checkpoints (deployed/, every ``output.checkpoint_every`` steps from the end of the release
on, at a stop and at the end) hold the full shell carried into the hybrid's configuration and,
beside it, the hybrid's own state (``tables.npz``: shell, beams, ties, velocities and
accelerations cell by cell, :meth:`HybridDeployment.state_tables`; in the meta the time, the
window's moves, the hub's state and the step size): ``--resume`` goes on from the last one as
if never stopped. A completed deployment is not recomputed; a checkpoint without the hybrid's
state (written during the release, or by an older tapecoil) deploys again from the release.
"""

from __future__ import annotations

import time
from pathlib import Path

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.measures.deployment import root_load_peaks
from tapecoil.phases.deployment_run import deployment_summary, step_figures
from tapecoil.phases.hybrid_deployment import DeploymentRecord, HybridDeployment
from tapecoil.phases.model_tag import HYBRID, KEY, by_hybrid
from tapecoil.phases.runner import LOG, Phase, run_phase
from tapecoil.phases.stepped import clock_origin, last_wall_time

__all__ = ["HybridDeploymentPhase", "run_hybrid_deployment"]


class HybridDeploymentPhase(Phase):
    """The deployment of ``coiling``'s tape (a coiled
    :class:`~tapecoil.phases.hybrid_coiling.HybridCoiling`) by the hybrid, written through
    ``model``'s full shell (a :class:`~tapecoil.phases.coiling.CoilingProblem` of the same
    configuration: the settled stowed state). ``restart``: a checkpoint's restart state, with
    ``deployment`` restored from it to go on with, or ``completed`` (its summary, nothing
    computed). ``stop``: as the full shell's deployment."""

    name, checkpoint_name, unit = "deployment", "deployed", "s"

    def __init__(
        self,
        config: Config,
        model,
        coiling=None,
        restart: dict | None = None,
        stop=None,
        deployment: HybridDeployment | None = None,
        completed: bool = False,
    ):
        super().__init__()
        self.config, self.model, self.coiling, self.stop = config, model, coiling, stop
        self.comm = model.comm
        self.target = config.deployment.t_end
        self.deployment = deployment
        self.moves: list = []
        self.placed_settling: list = []
        self.dofs = 0
        self._stowed_energy = 0.0
        self.completed = completed
        if restart is not None:
            self.history = list(restart["history"])
            self.moves = restart.get("moves", [])
            self.dofs = restart.get("dofs", 0)
            self._stowed_energy = restart.get("stowed_energy", 0.0)
        self._t0 = clock_origin(last_wall_time(self.history))

    # -- the runner's hooks ---------------------------------------------------------------------
    def position(self) -> float:
        return self.history[-1]["time"] if self.history else 0.0

    def _restartable(self) -> bool:
        """Whether the deployment's state can be gone on from (:meth:`HybridDeployment.released`)."""
        return self.deployment is not None and self.deployment.released()

    def restart_state(self) -> dict:
        deployment = self.deployment if self._restartable() else None
        return {
            KEY: HYBRID,
            "history": self.history,
            "moves": self.moves,
            "dofs": self.dofs,
            "stowed_energy": self._stowed_energy,
            "deployment": None if deployment is None else deployment.restart_state(),
        }

    def checkpoint_meta(self) -> dict:
        return {"hub_angle": self.model.root.angle, "tension": 0.0}

    def write_checkpoint(self, path: Path, meta: dict) -> None:
        """The full shell carried into the hybrid's configuration, with the hybrid's own state
        beside it (collective)."""
        tables = None
        if self.deployment is not None:
            self._carry()
        if self._restartable():
            tables = self.deployment.state_tables()
        self.model.tape.write_checkpoint(path, meta, tables=tables)

    def progress(self, row: dict) -> tuple[float, float, int, str, bool]:
        window = f" window {row['window_start']:.3f}-{row['window_end']:.3f} m"
        return (
            row["time"],
            row["step"],
            row["newton_iterations"],
            f" lambda {row['lambda']:.3f}{window}",
            self._restartable(),
        )

    def _row(self, record: DeploymentRecord) -> dict:
        total = record.energy
        if not self.history:
            self._stowed_energy = total
        return {
            "time": record.time,
            "step": record.step,
            "newton_iterations": record.iterations,
            "cutbacks": record.cutbacks,
            "rejected_steps": record.rejected_steps,
            "lambda": record.deployed,
            "coiled_length": record.coiled_length,
            # how loose the coil is: its opening behind the lift-off [m] and where [m], the
            # turns still wound beyond the lift-off
            "coil_opening": record.coil_opening,
            "coil_opening_at": record.coil_opening_at,
            "loose_turns": record.loose_turns,
            # the hub: its angle [rad] and rate [rad/s] (coiling sense), its kinetic energy (in
            # kinetic_energy too), and the angular momentum of tape and hub about its axis
            "hub_angle": record.hub_angle,
            "hub_rate": record.hub_rate,
            "hub_kinetic_energy": record.hub_kinetic_energy,
            "strain_energy": record.strain_energy,
            "contact_energy": record.contact_energy,
            "kinetic_energy": record.kinetic_energy,
            "external_work": record.external_work,
            # what the scheme and the window moves took out of the tape's energy (or put in)
            "dissipated_energy": self._stowed_energy + record.external_work - total,
            "angular_momentum": record.angular_momentum,
            # the force [N] and moment [N m] the tape exerts on the hub through its root
            **record.root_loads,
            "window_start": record.window[0],
            "window_end": record.window[1],
            "dofs": self.deployment.measures.dofs(),
            "wall_time": time.perf_counter() - self._t0,
        }

    def _add(self, record: DeploymentRecord) -> None:
        row = self._row(record)
        self.history.append(row)
        self.dofs = max(self.dofs, row["dofs"])
        count = len(self.history)
        if count % self.config.output.vtx_every == 0:
            self._carry()  # the runner writes the full shell after this row
        if self.on_row is not None:
            self.on_row(row)
        if self.stop is not None:
            self.stop.check(self.comm)

    def _carry(self) -> None:
        self.coiling.carry_into(self.model, self.deployment.hybrid, self.deployment.angle)

    def advance(self) -> None:
        d = self.config.deployment
        deployment = self.deployment
        if deployment is None:
            self._t0 = time.perf_counter()
            self.deployment = deployment = HybridDeployment(self.coiling, self.config)
            LOG.info(
                "deployment with the hybrid: generalized-alpha, rho_inf = %g, to lambda = %g, window %g-%g m",
                deployment.rho_inf,
                d.lambda_end,
                *deployment.window(),
            )
            self._add(deployment.record())
        try:
            outcome = deployment.run(self._add)
            self.completed = outcome == "deployed"
            if not self.completed:
                self.message = f"t_end = {d.t_end:g} s reached before lambda = {d.lambda_end:g}"
        finally:
            self.moves = [list(m) for m in deployment.moves]
            self.placed_settling = deployment.placed_settling
            self._carry()  # the last converged state, for the final files
            deployment.destroy()

    def summary(self, interrupted, t_start: float) -> dict:
        """The deployment's summary: the full shell's measures against the theory, from the
        hybrid's history, and the run's figures."""
        history = self.history
        res = self.model.tape.strip.resolution
        placed = self.placed_settling
        return {
            **deployment_summary(self, interrupted, self.config, self.config.deployment.rho_inf, "alpha"),
            # (a checkpoint of a hybrid run from before the root's loads were read has none)
            **(root_load_peaks(history) if "root_torque" in history[0] else {}),
            "run": {
                KEY: HYBRID,
                "ranks": self.comm.size,
                "dofs": self.dofs,
                "mesh": f"{res.along} x {res.across}",
                **step_figures(history),
                "window_moves": max(len(self.moves) - 1, 0),
                "account": (
                    "Deployed by the hybrid from its own coiled state, its shell window following "
                    f"the lift-off down the coil ({max(len(self.moves) - 1, 0)} moves; DOFs above at "
                    "their most). The pictures and snapshots are the hybrid's state carried into the "
                    "full shell; the root's loads are the reaction of the flattened beam's clamped "
                    "root node, and of the window's root edge once the window reaches the root."
                ),
                "placed_sections_settled": {
                    "newton_iterations": int(sum(p["iterations"] for p in placed)),
                    "largest_displacement": max((p["moved"] for p in placed), default=0.0),
                    "strain_energy_released": float(
                        sum(p["strain_energy_placed"] - p["strain_energy_settled"] for p in placed)
                    ),
                },
                "wall_time": history[-1]["wall_time"],
                "process_wall_time": time.perf_counter() - t_start,
            },
        }


def run_hybrid_deployment(
    config: Config,
    directory: str | Path,
    model,
    coiling=None,
    comm=MPI.COMM_WORLD,
    progress: bool = True,
    stop=None,
    resume: str | Path | None = None,
) -> dict:
    """Deploy ``coiling``'s tape (a coiled :class:`~tapecoil.phases.hybrid_coiling.HybridCoiling`)
    with the hybrid into ``directory``, its files written through ``model``'s full shell (the
    settled stowed :class:`~tapecoil.phases.coiling.CoilingProblem`); returns the phase summary.
    ``resume``: a deployment checkpoint to go on from as if never stopped (``coiling`` is the
    coil it deploys); a completed hybrid one gives its summary again; one without the hybrid's
    state deploys again from the release (``coiling`` is needed in both)."""
    from tapecoil.core.checkpoint import read_meta, read_tables

    t_start = time.perf_counter()
    if resume is not None:
        meta = read_meta(resume)
        restart = meta.get("run") or {}
        ours = by_hybrid(restart)
        if meta.get("completed") and ours:
            LOG.info("hybrid deployment: completed in %s", resume)
            phase = HybridDeploymentPhase(config, model, restart=restart, completed=True)
            return phase.summary(None, t_start)
        tables = read_tables(resume)
        if ours and coiling is not None and tables is not None and restart.get("deployment"):
            deployment = HybridDeployment(coiling, config, restart=restart["deployment"], tables=tables)
            LOG.info("hybrid deployment resumed from %s at t = %.6g s", resume, deployment.time)
            phase = HybridDeploymentPhase(config, model, coiling, restart, stop, deployment=deployment)
            return run_phase(phase, directory, config, comm, model.model, restart, progress, t_start)
        LOG.warning(
            "hybrid deployment: %s holds no hybrid state to go on from; deploying again from the release",
            resume,
        )
    if coiling is None:
        raise ValueError("the hybrid deploys the tape its own coiling left: coil with the hybrid first")
    phase = HybridDeploymentPhase(config, model, coiling, stop=stop)
    return run_phase(phase, directory, config, comm, model.model, None, progress, t_start)
