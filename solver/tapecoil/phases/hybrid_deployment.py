"""The deployment of a tape coiled by the shell-beam hybrid, with the hybrid itself: the shell
window follows the ploy region down the coil as the tape unwinds.

The start is a :class:`~tapecoil.phases.hybrid_coiling.HybridCoiling` at its final hub angle,
in equilibrium with the guide and the pull at the free end. At release the window is rebuilt
to the free end (it is there already when the coil leaves less than ``window_ahead`` free),
from where it starts or, if that holds less, from ``window_release`` of coil behind the
lift-off (a coil shorter than that keeps the coiling's window): the release sends a wave of lift
down the coil, which the flattened beam behind the window cannot follow. The free end is let
go, the state carried over
(:func:`~tapecoil.models.window.carry_over`), a grown window settled whole at rest
(:func:`~tapecoil.models.window_settling.settle_at_rest`), and the end is held by the full shell's release
hold (:class:`~tapecoil.phases.release.EndHold`: a spring to the stowed end and the dead
forces that held it there, let go over ``deployment.release_time``). The hub is held at its
stowed angle (``deployment.hub = "fixed"``) or free to turn with its rotary inertia ``hub.inertia``
(``"free"``: :mod:`tapecoil.phases.hybrid_free_hub`, from the torque the tape held it with);
the root stays clamped to it; with ``deployment.gravity`` the shell and the beam
carry their weight from release (starting to fall at g where the hold does not hold them:
:meth:`~tapecoil.phases.hybrid_motion.HybridMotion.start_falling`); the flattened beam on the
coil and the window's
shell rest on the spiral of turns, their winding angles read from the state after every step,
as in coiling.

The shell and the beam are stepped together by generalized-alpha
(:class:`~tapecoil.phases.hybrid_motion.HybridMotion`) with the deployment's settings: its
spectral radius, its first and largest steps, the release's steps of at most a twentieth of it,
growth after easy solves and cut-back after failed ones, and, with ``deployment.error_tolerance``,
steps sized by their local error (the shell's and the beam's displacements together, as the
full shell's :meth:`~tapecoil.phases.deployment.DeploymentProblem.step_error`), in the time loop
both models share (:mod:`tapecoil.phases.time_loop`). A step whose Newton solve converges to
more energy than the step started with is refused and cut back
(:meth:`HybridDeployment.step_refusal`).

As the tape unwinds the lift-off point travels towards the root. Once the release is over and
the lift-off has come within ``window_behind`` of the window's start, the window moves back
along the tape: a new hybrid is built whose window, of its own length, starts ``window_behind +
window_move`` behind the lift-off (so that the shell always holds at least ``window_behind`` of
the coil behind the lift-off, and at least ``window_ahead - window_move`` of tape beyond it, as
in coiling, where the lift-off travels the other way), and the state and the rates (velocities and
accelerations) are carried over by :func:`~tapecoil.models.window_motion.carry_motion`; shell becomes
beam ahead of the ploy region, towards the free end, and beam becomes shell on the coil. The
sections placed into shell from the flattened beam are then settled
(:func:`~tapecoil.models.window_settling.settle_placed`), and so are the arc beam's nodes fitted
to the shell's sections ahead (:func:`~tapecoil.models.window_settling.settle_withdrawn`).

After every step the deployment reads its measures
(:class:`~tapecoil.phases.hybrid_deployment_measures.HybridDeploymentMeasures`): the energies, the
tape's angular momentum about the hub's axis, the deployed fraction, the full shell's measure read
on the hybrid's centre line, and the flattened beam's gap to its turn behind the window.

The hybrid holds the tape behind the window flat on its turns (by default, ``model.beam_contact
= "width"``, the flattened beam rests on them across its width: by its line alone its section
turns, and the 2 m benchmark tape's coil came loose a third of a second after release).
Where the coil loosens within ``window_behind + window_move`` behind the window's start, the
stretch that the next moves place into shell (the flattened beam, beyond its first turn,
lifted off the turn beneath by more than the lift-off gap), the run stops
(:class:`CoilLoosening`) with its last converged state rather than place shell sections from
a lifted beam.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from tapecoil.config.model import hybrid_need
from tapecoil.contact.term import linear_solver_options
from tapecoil.core.cell_state import gather_fields, scatter_fields
from tapecoil.core.coupled_newton import JointState
from tapecoil.core.dofs import owned_size
from tapecoil.core.stepping import ContinuationError
from tapecoil.hub.rotor import HubRotor
from tapecoil.measures.deployment import LIFT_OFF_GAP
from tapecoil.models.beam_section import BeamSection
from tapecoil.models.nodes import Nodes
from tapecoil.models.window import carry_over
from tapecoil.models.window_motion import carry_motion
from tapecoil.models.window_settling import settle_at_rest, settle_placed, settle_withdrawn
from tapecoil.phases.free_hub import section_moment
from tapecoil.phases.hybrid_deployment_measures import HybridDeploymentMeasures, coiled_along
from tapecoil.phases.hybrid_free_hub import HybridFreeHub
from tapecoil.phases.hybrid_motion import HybridMotion
from tapecoil.phases.release import EndHold
from tapecoil.phases.root_loads import HybridRootLoads
from tapecoil.phases.stepped import clock_origin, last_wall_time
from tapecoil.phases.time_loop import (
    Deployed,
    StepOn,
    TimeStepper,
    energy_refusal,
    step_error,
    step_in_time,
    time_legs,
)

__all__ = ["CoilLoosening", "DeploymentRecord", "HybridDeployment", "deployment_options"]

# the rates are carried over a window move along the motion's path over this share of the time
# an element's length takes at the tape's fastest speed (central differences: their second order
# error is about 1e-6 of the rates, the rounding of the acceleration's difference far below it)
PROBE_SHARE = 1e-3


def deployment_options(config) -> dict:
    """The PETSc options (without prefix) of the hybrid's joint solvers in time: the linear solve
    the contact needs (the turns' real contact is not a Hessian's: LU and its applied part in
    GMRES, :func:`~tapecoil.contact.term.linear_solver_options`), then ``[solver]`` and
    ``[deployment]`` petsc_options."""
    return {
        **linear_solver_options(config.contact.turns == "surface"),
        **config.solver.petsc_options,
        **config.deployment.petsc_options,
    }


@dataclass
class DeploymentRecord:
    """A converged step of the hybrid's deployment: time [s], the step to it [s], the deployed
    fraction lambda and the coiled length [m], the window (start, end) [m] along the tape, the
    strain, contact and kinetic energy [J] (the ties' penalty apart; a free hub's kinetic
    energy in it too), the work of the loads on the tape since release (the release's hold,
    gravity) [J], the step's Newton iterations, cut-backs and rejected steps, the wall time since
    release [s], the angular momentum of the tape and a free hub about the hub's axis
    [kg m^2/s], the root's loads on the hub
    (:class:`~tapecoil.phases.root_loads.HybridRootLoads`: ``root_force_x`` ... ``root_torque``
    [N], [N m]), the hub's angle [rad], rate [rad/s] (coiling sense) and kinetic energy [J]
    (a held hub's: its stowed angle, 0, 0), and how loose the coil is: its opening behind the
    lift-off and where [m], the loose turns beyond it
    (:func:`~tapecoil.measures.deployment.coil_looseness`; 0 in records written before them)."""

    time: float
    step: float
    deployed: float
    coiled_length: float
    window: tuple[float, float]
    strain_energy: float
    contact_energy: float
    kinetic_energy: float
    external_work: float
    iterations: int
    cutbacks: int
    rejected_steps: int
    wall_time: float
    angular_momentum: float
    root_loads: dict
    hub_angle: float
    hub_rate: float
    hub_kinetic_energy: float
    coil_opening: float = 0.0
    coil_opening_at: float = 0.0
    loose_turns: float = 0.0

    @property
    def energy(self) -> float:
        """The strain, contact and kinetic energy [J] (a free hub's in the kinetic)."""
        return self.strain_energy + self.contact_energy + self.kinetic_energy


class CoilLoosening(ContinuationError):
    """The coil loosens behind the window: a stretch of the flattened beam has lifted off its
    turn by more than the lift-off gap. A tape that leaves the coil takes back its arc section,
    which the flattened beam cannot do, and a move would place shell sections from it (twisted,
    into the turns): the hybrid stops there, its last converged state kept."""


def _deploying(coiled, config):
    """``config`` for the deployment of a tape coiled under ``coiled`` (both
    :class:`~tapecoil.config.Config`); ValueError where they differ in more than what acts from
    the release on (or acts on no computation: the [output] table, ``model.kind``)."""
    same = dataclasses.replace(
        config,
        deployment=coiled.deployment,
        hub=dataclasses.replace(config.hub, inertia=coiled.hub.inertia),
        model=dataclasses.replace(
            config.model, window_release=coiled.model.window_release, kind=coiled.model.kind
        ),
        output=coiled.output,
    )
    if same != coiled:
        differ = [
            f.name for f in dataclasses.fields(coiled) if getattr(same, f.name) != getattr(coiled, f.name)
        ]
        raise ValueError(
            f"the hybrid deploys the tape as it was coiled: the configuration differs from the "
            f"coiling's in [{'], ['.join(differ)}] (only [deployment], hub.inertia and "
            "model.window_release act from the release on; [output] and model.kind on nothing)"
        )
    return config


class HybridDeployment:
    """The deployment of ``coiling``'s tape (a :class:`~tapecoil.phases.hybrid_coiling.HybridCoiling`
    at its final hub angle) with the hybrid (see the module). :meth:`run` steps to
    ``deployment.lambda_end`` or ``deployment.t_end``; ``records`` holds a row per converged
    step, ``moves`` the window's places, (time, start, end), and ``measures`` the present
    window's :class:`~tapecoil.phases.hybrid_deployment_measures.HybridDeploymentMeasures`
    (energies, angular momentum, lift-off, DOFs). The joint solvers read PETSc
    options under ``hybrid_deploy<k>_``, k the window's number from 0; ``solver.petsc_options``
    and ``deployment.petsc_options`` reach all of them.

    ``config``: the deployment's configuration, by default the coiling's. It may differ from
    the coiling's in its [deployment] table, ``hub.inertia`` and ``model.window_release``, which
    act from the release on, so that one coiled tape deploys under several settings; the
    coiling is left as it was. ``restart``, ``tables``: go on instead from a deployment of this
    coiling as :meth:`restart_state` and :meth:`state_tables` left it, after its release."""

    def __init__(self, coiling, config=None, restart: dict | None = None, tables: dict | None = None):
        self.coiling = coiling
        self.config = cfg = coiling.config if config is None else _deploying(coiling.config, config)
        self.comm = coiling.comm
        d = cfg.deployment
        need = hybrid_need(cfg)
        if need is not None:
            raise ValueError(f"the hybrid deploys only with {need}")
        self.rho_inf = d.rho_inf
        self.angle = coiling.angle
        tp = cfg.tape
        arc = BeamSection.circular_arc(tp.R, tp.alpha, tp.h, tp.E, tp.nu)
        self.line_density = tp.rho_l
        # the section's mass moments of inertia per unit length: density times its second
        # moments, the arc's (the flattened strip's differ, but its turns barely spin)
        self.rotary_inertia = tp.density * np.array([arc.EI2 + arc.EI3, arc.EI2, arc.EI3]) / tp.E
        self.options = deployment_options(cfg)
        self.time = 0.0
        self.external_work = 0.0
        # the flattened beam's largest gap to its turn behind the window [m] and where [m]
        self.beam_gap = (0.0, 0.0)
        self.records: list[DeploymentRecord] = []
        # the release's settling of a grown window and each move's of the sections placed
        # from the beam (window_settling.settle's figures)
        self.placed_settling: list[dict] = []
        self.moves: list[tuple[float, float, float]] = []
        self.next_step: float | None = None  # the step the stepping tries next
        self.outcome = "t_end"
        # the tape's energy at the start of the step under way [J] (:meth:`step_refusal`)
        self._start_energy = 0.0
        self._resumed = restart is not None
        if restart is not None:
            self._restore(restart, tables)
            return
        old = coiling.hybrid
        # the window reaches the free end, whose hold the release lets go, and holds at least
        # window_release of the coil behind the lift-off, where the release's wave runs; a
        # coil shorter than that keeps the coiling's window, and its flattened beam at the root
        lift = coiled_along(old, coiling.frame, self.angle, tp)[-1]
        element = coiling.element
        wanted = element * math.floor((lift - cfg.model.window_release) / element + 1e-9)
        old_start, old_end = old.shell.surface.xi_range[0]
        start = min(old_start, wanted) if wanted > 0 else old_start
        if start <= 0.0:
            raise ValueError(
                f"the hybrid cannot deploy this coil: its coiled length, {lift:.4g} m, is shorter "
                f"than model.window_behind + model.window_move = {coiling.window.behind + coiling.move:g} m, "
                "so its window never left the root and would hold the whole tape at release, "
                "nothing of it beam; coil further, or deploy it with model.kind = 'shell'"
            )
        self.hybrid = coiling.build(start, self._name(), released=True, end=tp.L)
        carry_over(old, self.hybrid)
        coiling.carry_winding(old, self.hybrid)
        if start < old_start or old_end < tp.L:
            # the tape at rest, its end where the guide held it: the window grown on the coil
            # and towards the free end settles whole, so that the release starts from rest and
            # the hold's dead forces are what holds the end there
            self.placed_settling.append(settle_at_rest(self.hybrid, cfg))
            self._check_settled(self.placed_settling[-1], "the window grown at release did not settle")
        self.hold = None
        self.rotor = self.free_hub = None
        self.motion = self._motion(self.hybrid, release=True)
        if d.hub == "free":
            self.rotor = HubRotor(cfg.hub.inertia, self.motion.shell_scheme.parameters, self.angle)
            self.free_hub = self._free_hub(self.motion)
            # at rest the schemes' levels hold the internal forces alone, at any step
            for scheme in self.motion.schemes:
                scheme.set_step(d.dt)
            self.free_hub.start()
        if np.any(self.motion.gravity):
            self.motion.start_falling()
        self.moves.append((0.0, *self.window()))

    # -- restart -------------------------------------------------------------------------------
    def restart_state(self) -> dict:
        """What, beside :meth:`state_tables`, this deployment needs to go on from its last
        converged step as if never stopped (JSON-ready; after the release: the hold's gone)."""
        return {
            "time": self.time,
            "hub_angle": self.angle,
            "external_work": self.external_work,
            "beam_gap": list(self.beam_gap),
            "next_step": self.next_step,
            "moves": [list(move) for move in self.moves],
            "placed_settling": self.placed_settling,
            "records": [dataclasses.asdict(record) for record in self.records],
            "rotor": None if self.rotor is None else self.rotor.state(),
        }

    def state_tables(self) -> dict[str, np.ndarray]:
        """The hybrid's state (:meth:`HybridProblem.state_tables`) with the velocities and
        accelerations of shell and beam, on rank 0 (collective)."""
        tables = self.hybrid.state_tables()
        tables.update(gather_fields(self._rate_fields(), self.comm))
        return tables

    def _rate_fields(self) -> dict:
        """The motion's velocities and accelerations as cell fields, named as in the tables."""
        return {f"field:motion:{name}": field for name, field in self.motion.rate_fields().items()}

    def released(self) -> bool:
        """Whether the release is over, its hold let go: from then on the state is one a restart
        goes on from (a restored deployment has no hold)."""
        return self.time >= self.config.deployment.release_time * (1 - 1e-12)

    def _restore(self, state: dict, tables: dict) -> None:
        self.time, self.angle = float(state["time"]), float(state["hub_angle"])
        if not self.released():
            raise ValueError("a hybrid deployment goes on from a state after its release only")
        self.external_work = float(state["external_work"])
        self.beam_gap = tuple(state["beam_gap"])
        self.next_step = state["next_step"]
        self.moves = [tuple(move) for move in state["moves"]]
        self.placed_settling = list(state["placed_settling"])
        self.records = [DeploymentRecord(**{**r, "window": tuple(r["window"])}) for r in state["records"]]
        self._start_energy = self.records[-1].energy
        _, start, end = self.moves[-1]
        self.hybrid = self.coiling.build(start, f"hybrid_deploy{len(self.moves) - 1}", released=True, end=end)
        self.hybrid.set_state(tables)
        # the hold has let go: its terms were zero since the release
        self.hold = self.rotor = self.free_hub = None
        self.motion = self._motion(self.hybrid, release=False)
        scatter_fields(self._rate_fields(), tables)
        self.motion.restart_rates()
        if state["rotor"] is not None:
            self.rotor = HubRotor(self.config.hub.inertia, self.motion.shell_scheme.parameters, self.angle)
            self.rotor.restore(state["rotor"])
            self.free_hub = self._free_hub(self.motion)

    # -- the hybrid and its motion -------------------------------------------------------------
    def _name(self) -> str:
        return f"hybrid_deploy{len(self.moves)}"

    def window(self) -> tuple[float, float]:
        """The shell window's start and end along the tape [m]."""
        return self.measures.window()

    def _motion(self, hybrid, release: bool) -> HybridMotion:
        cfg = self.config

        def hold_loads(scheme):
            self.hold = EndHold(hybrid.shell, scheme, cfg.deployment.release_time)
            return self.hold.form, [self.hold.point_force()]

        motion = HybridMotion(
            hybrid,
            cfg.tape,
            self.line_density,
            self.rotary_inertia,
            rho_inf=self.rho_inf,
            settings=cfg.deployment.newton(cfg.solver),
            options=self.options,
            loads=hold_loads if release else None,
            gravity=cfg.deployment.gravity,
        )
        motion.set_load(self.angle)
        reach = self.coiling.window.behind + self.coiling.move
        self.measures = HybridDeploymentMeasures(
            hybrid, motion, self.coiling.frame, self.angle, cfg.tape, reach
        )
        self.root_loads = HybridRootLoads.in_time(motion, self.coiling.frame)
        if self.rotor is not None:
            self.free_hub = self._free_hub(motion)
        return motion

    def _free_hub(self, motion) -> HybridFreeHub:
        """The free hub's equation solved with ``motion``'s."""
        return HybridFreeHub(motion, self.rotor, section_moment(self.config))

    # -- stepping -------------------------------------------------------------------------------
    def step_error(self) -> float:
        """The step's local error over its tolerance, the shell's and the beam's translations
        together (:func:`~tapecoil.phases.time_loop.step_error`; collective; before the advance)."""
        cfg = self.config
        return step_error(self._translations(), cfg.deployment.error_tolerance, cfg.tape.h, self.comm)

    def step_refusal(self) -> str | None:
        """Why a converged step is not accepted for the energy it made
        (:func:`~tapecoil.phases.time_loop.energy_refusal`), None if it is: the strain, contact
        and kinetic energy of shell, beam and a free hub at the step's end, its rates as the
        schemes will take them, against the step's start less the loads' work over the step
        (collective; before the step is committed)."""
        records, motion, m = self.records, self.motion, self.measures
        if not records:  # no record of the release yet: nothing to compare with
            return None
        saved = [scheme.v_old.x.array.copy() for scheme in motion.schemes]
        try:
            for scheme in motion.schemes:
                scheme.v_old.x.array[:] = scheme.new_rates()[0]
            kinetic = m.kinetic_energy()
        finally:
            for scheme, v in zip(motion.schemes, saved, strict=True):
                scheme.v_old.x.array[:] = v
        if self.rotor is not None:
            kinetic += 0.5 * self.rotor.inertia * self.rotor.new_rates()[0] ** 2
        after = m.strain_energy() + m.contact_energy() + kinetic
        work = (0.0 if self.hold is None else self.hold.work()) + motion.weight_work()
        return energy_refusal(self._start_energy, after, work, records[0].energy)

    def _translations(self):
        """(scheme, owned translational dofs) of the shell and the beam."""
        shell, beam = self.hybrid.shell, self.hybrid.beam.model
        shell_u = shell.contact.nodes.u_dofs.ravel()
        beam_u = beam.node_u_dofs.ravel()
        return (
            (self.motion.shell_scheme, np.unique(shell_u[shell_u < owned_size(shell.model.W)])),
            (self.motion.beam.scheme, np.unique(beam_u[beam_u < owned_size(beam.W)])),
        )

    def _wanted_start(self, lift: float) -> float | None:
        """The window's new start [m] for the lift-off at ``lift`` [m], None to stay: once the
        lift-off has come within ``behind`` of the start, ``behind + move`` behind it (on the
        elements' grid), so that, as in coiling, at least ``behind`` of the coil is always shell."""
        if self.time < self.config.deployment.release_time:
            return None
        return self.coiling.start_back(lift, self.window()[0])

    def _move(self, start: float) -> None:
        old, motion = self.hybrid, self.motion
        rates = motion.rates()
        before = self.measures.energies()
        # the fastest node's speed (the translations'; the directors' angles may spin fast)
        speeds = (rates[0][Nodes(old.shell.model).u_dofs], rates[2][old.beam.model.node_u_dofs])
        fastest = self.comm.allreduce(max(float(np.abs(v).max(initial=0.0)) for v in speeds), op=MPI.MAX)
        probe = PROBE_SHARE * self.coiling.element / max(fastest, 1e-3)
        new = self.coiling.build(start, self._name(), released=True)
        new_rates = carry_motion(old, new, rates, probe)
        self.coiling.carry_winding(old, new, self.angle)
        old_window = old.shell.surface.xi_range[0]
        settling = settle_placed(new, old_window, self.config)
        self._check_settled(settling, "the sections placed from the beam did not settle on the shell")
        new_end = new.shell.surface.xi_range[0][1]
        withdrawn = settle_withdrawn(new, (new_end, old_window[1]), self.config)
        self._check_settled(withdrawn, "the beam's nodes fitted to the shell did not settle")
        settling.update({f"withdrawn_{k}": v for k, v in withdrawn.items()})
        motion.destroy()
        self.hold = None  # moved after the release: the end is free
        self.hybrid = new
        self.motion = self._motion(new, release=False)
        self.motion.set_rates(new_rates)
        after = self.measures.energies()
        hub_kinetic = 0.0 if self.rotor is None else self.rotor.kinetic_energy()
        self._start_energy = sum(after.values()) + hub_kinetic
        self.placed_settling.append(
            {
                **settling,
                **{f"{k}_before": v for k, v in before.items()},
                **{f"{k}_after": v for k, v in after.items()},
            }
        )
        self.moves.append((self.time, *self.window()))

    def _check_settled(self, settling: dict, failure: str) -> None:
        """Stop, the last converged state kept, where what a window move placed or fitted did not
        settle (``failure`` says which): stepping on from it would release its strain as a
        vibration."""
        if not settling["converged"]:
            raise ContinuationError(
                f"the hybrid's window move at t = {self.time:.6g} s: {failure} "
                f"({settling['iterations']} Newton "
                "iterations); deploy this tape with the full shell (model.kind = 'shell'), or "
                f"with a finer mesh. Last converged time {self.time:.6g} s",
                self.time,
            )

    def _commit(self, motion) -> None:
        if self.hold is not None:  # its work over the step, before the state moves on
            self.external_work += self.hold.work()
        self.external_work += motion.weight_work()
        motion.commit_step()
        if self.rotor is not None:
            self.rotor.advance()
            self.angle = self.measures.hub_angle = self.rotor.angle

    def record(self, step=None, t0: float | None = None) -> DeploymentRecord:
        """The state's record (collective): of the converged ``step`` (a
        :class:`~tapecoil.core.stepping.StepRecord`), or of the release (no step); the wall time
        from ``t0`` (:func:`time.perf_counter`)."""
        m, rotor = self.measures, self.rotor
        hub_kinetic = 0.0 if rotor is None else rotor.kinetic_energy()
        reading = m.lift_off()
        self.beam_gap = (reading["beam_gap"], reading["beam_gap_at"])
        record = DeploymentRecord(
            self.time,
            0.0 if step is None else float(step.step),
            reading["lambda"],
            reading["coiled_length"],
            self.window(),
            m.strain_energy(),
            m.contact_energy(),
            m.kinetic_energy() + hub_kinetic,
            self.external_work,
            0 if step is None else int(step.iterations),
            0 if step is None else int(step.cutbacks),
            0 if step is None else int(step.rejected),
            0.0 if t0 is None else time.perf_counter() - t0,
            m.angular_momentum() + (0.0 if rotor is None else rotor.angular_momentum()),
            self.root_loads(),
            self.angle,
            0.0 if rotor is None else rotor.rate,
            hub_kinetic,
            reading["coil_opening"],
            reading["coil_opening_at"],
            reading["loose_turns"],
        )
        self._start_energy = record.energy  # the next step's start
        return record

    def run(self, on_step=None) -> str:
        """Release and step to ``deployment.lambda_end`` (returns "deployed") or ``t_end``
        ("t_end"); ``on_step(record)`` after each converged step. Raises
        :class:`~tapecoil.core.stepping.ContinuationError` when a step does not converge even cut
        back, the last converged state kept."""
        d = self.config.deployment
        t0 = clock_origin(last_wall_time(self.records) if self._resumed else 0.0)
        legs = time_legs(d.release_time, d.t_end, d.dt, d.max_dt)
        if len(legs) == 1 and self.hold is not None:  # no release leg: the end let go at once
            self.hold.release(0.0)

        def converged(step, end):
            self.time = step.load
            self.next_step = step.next_step if step.load < end else None
            record = self.record(step, t0)
            self.records.append(record)
            if on_step is not None:
                on_step(record)
            self._after_step(record)

        if self._resumed and self.records:
            # what the stopped run did after its last step: stop there, or move the window
            self._resumed = False
            try:
                self._after_step(self.records[-1])
            except StepOn:
                pass
            except Deployed:
                return self.outcome
        try:
            step_in_time(self.config, legs, self, self.stepper, converged)
        except Deployed:
            pass
        except ContinuationError:
            if self.free_hub is not None:  # the root back where the last converged step left it
                self.free_hub.place(self.rotor.angle)
            raise
        return self.outcome

    def _after_step(self, record: DeploymentRecord) -> None:
        """After a converged step: raise :class:`~tapecoil.phases.time_loop.Deployed` when the
        tape is deployed (``outcome``), :class:`~tapecoil.phases.time_loop.StepOn` when the window
        moved, :class:`CoilLoosening` when the coil has come loose behind it."""
        cfg = self.config
        if record.deployed >= cfg.deployment.lambda_end:
            self.outcome = "deployed"
            raise Deployed
        gap, at = self.beam_gap
        if gap > LIFT_OFF_GAP * cfg.tape.h:
            raise CoilLoosening(
                f"the coil loosens behind the hybrid's window at t = {self.time:.6g} s "
                f"(lambda = {record.deployed:.4g}): the flattened beam at s = {at:.4g} m has "
                f"lifted {gap / cfg.tape.h:.3g} thicknesses off its turn (the window starts at "
                f"{self.window()[0]:.4g} m). A tape that leaves the coil takes back its arc "
                "section, which the flattened beam cannot; deploy this tape with the full "
                "shell (model.kind = 'shell'). Last converged time "
                f"{self.time:.6g} s",
                self.time,
            )
        start = self._wanted_start(record.coiled_length)
        if start is not None:
            self._move(start)
            raise StepOn

    def stepper(self) -> TimeStepper:
        """The present window's motion as the time loop steps it."""
        motion = self.motion
        alpha_f = motion.shell_scheme.parameters.alpha_f

        def set_step(dt, target):
            for scheme in motion.schemes:
                scheme.set_step(dt)
            if self.hold is not None:
                self.hold.release(target - alpha_f * dt)

        def predict(dt):
            for scheme in motion.schemes:
                scheme.predict(dt)
            if self.rotor is not None:
                self.rotor.predict(dt)

        return TimeStepper(
            JointState(self.hybrid.shell.model.q, self.hybrid.beam.model.q),
            motion.solver.solve if self.free_hub is None else self.free_hub.solve,
            set_step,
            predict,
            self.step_error,
            self.step_refusal,
            commit=lambda: self._commit(motion),
        )

    def destroy(self) -> None:
        self.motion.destroy()
