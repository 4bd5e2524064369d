"""Quasi-static coiling with the shell-beam hybrid: shell around the ploy region, beam elsewhere.

The tape is shell only on a window around the ploy region
(:class:`~tapecoil.phases.window_on_hub.WindowOnHub`), the
geometrically exact beam elsewhere (:mod:`tapecoil.models.tape_beam`), the two tied as rigid
sections (:class:`~tapecoil.models.hybrid_problem.HybridProblem`):

- At the start the window is the root's: the root is attached to the hub and flattened onto it
  as in the full shell's coiling (:mod:`tapecoil.phases.coiling`), the beam of the arc section
  runs beyond the window, tied to its far edge as the arc, its end on the guide line and pulled
  by T (``coiling.tension``).
- The hub turns and the lift-off point, where the tape leaves the coil, travels along the
  material. Once it is ``WindowSettings.move`` further on, the window moves with it
  (:func:`~tapecoil.models.window.carry_over`): the coiled shell behind becomes a beam of the
  flattened strip's section (fitted to the shell's sections; the coil's free edges' relief in
  its energy), clamped to the hub at the root and kept off the hub and the turns beneath by the
  same spiral obstacle as the shell (``contact.turns = "spiral"``, its line a half thickness
  above the face that touches); it is tied flat to the window. The beam ahead becomes shell.
- Each point's winding angle, which places it on the spiral, is carried over by unwrapping the
  polar angle along the tape from the root.

The window holds ``behind`` of coil and ``ahead`` of tape beyond the lift-off: the ploy region,
where the section goes from flat to the arc, lies there (docs/notes/hybrid.md gives the
measurements behind the defaults). Once the window reaches the free end it stays there, the
free end's guide and pull on the shell.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.config.model import hybrid_coiling_need
from tapecoil.contact.surface import BeamStripSurface, JoinedSurface, ShellSurface
from tapecoil.contact.term import linear_solver_options
from tapecoil.core.dofs import global_size
from tapecoil.core.stepping import ContinuationError
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.hub.contact import ContactSettings, root_fairing, spiral_obstacle
from tapecoil.hub.frame import HubFrame
from tapecoil.measures.payout import OUTER_STATION, STATION_MARGIN, outer_station
from tapecoil.models.beam_section import BeamSection
from tapecoil.models.hybrid_problem import HybridProblem
from tapecoil.models.solver_terms import relaxation_scale
from tapecoil.models.tape_beam import tape_beam
from tapecoil.models.window import carry_over, full_shell
from tapecoil.models.window_settling import settle_placed
from tapecoil.phases.coiling_run import CoilingRun
from tapecoil.phases.hybrid_line import centre_line, winding_along
from tapecoil.phases.predictors import choose_predictor, wound_length
from tapecoil.phases.root_loads import HybridRootLoads
from tapecoil.phases.stepped import EASY_ITERATIONS, clock_origin, last_wall_time
from tapecoil.phases.turn_contact import TurnContact
from tapecoil.phases.window_on_hub import WindowOnHub

__all__ = ["HybridCoiling", "WindowSettings"]


@dataclass(frozen=True)
class WindowSettings:
    """Where the hybrid's shell window lies in coiling.

    Attributes:
        ahead: shell beyond the lift-off point [m] (the ploy region and a margin).
        behind: shell on the coil behind the lift-off point [m] (the flat tie's place).
        move: how far the lift-off travels before the window moves with it [m] (rounded up to
            whole elements).
        tie_penalty: the ties' penalty factor (:class:`~tapecoil.models.interface.RigidSectionTie`).
        beam_contact: the flattened beam on the turns by its "line" or across its "width".
    """

    ahead: float
    behind: float
    move: float
    tie_penalty: float
    beam_contact: str

    @classmethod
    def from_config(cls, model) -> WindowSettings:
        """From a :class:`~tapecoil.config.ModelConfig` (the [model] table)."""
        return cls(
            model.window_ahead,
            model.window_behind,
            model.window_move,
            model.tie_penalty,
            model.beam_contact,
        )


@dataclass
class CoilingRecord:
    """A converged step of the hybrid's coiling: the hub angle [rad] and the step to it [rad],
    the window (start, end) [m] along the tape, the lift-off's place along it [m], the strain
    energy [J], the step's Newton iterations and the wall time since the run began [s]."""

    hub_angle: float
    step: float
    window: tuple[float, float]
    lift_off: float
    strain_energy: float
    iterations: int
    wall_time: float


class HybridCoiling:
    """The coiling of ``config``'s tape with the hybrid model (see the module): :meth:`flatten`,
    then :meth:`coil` to a hub angle; ``records`` holds a row per converged step and ``moves``
    the window's places, (hub angle, start, end). ``window``: by default the [model] table's
    (``config.model``). Hub-angle steps from ``first_step`` up to
    ``max_step`` [rad] (by default the full shell's coiling's: ``coiling.max_step``, else its
    predictor's). Each window's joint solver reads PETSc options under the prefix
    ``hybrid_coil<k>_``, k the window's number from 0; ``solver.petsc_options`` and
    ``coiling.petsc_options`` reach all of them. ``restart`` and ``tables``: a
    :meth:`restart_state` and the tables of its hybrid to go on from (:meth:`restore`), its
    window built where it was instead of at the root."""

    def __init__(
        self,
        config: Config,
        comm=MPI.COMM_WORLD,
        window: WindowSettings | None = None,
        first_step: float = 0.1,
        max_step: float | None = None,
        restart: dict | None = None,
        tables: dict | None = None,
    ):
        self.config, self.comm = config, comm
        self.window = window or WindowSettings.from_config(config.model)
        self.first_step, self.max_step = first_step, max_step
        config = self.config
        tp, cc = config.tape, config.contact
        need = hybrid_coiling_need(config)
        if need is not None:
            raise ValueError(f"the hybrid coils only with {need}")
        resolution = MeshResolution.from_config(config.mesh, tp.L)
        self.element = tp.L / resolution.along
        self.window_length = self.element * math.ceil((self.window.ahead + self.window.behind) / self.element)
        if self.window_length >= tp.L:
            raise ValueError(
                f"the hybrid's window ({self.window_length:g} m) must be shorter than the tape "
                f"(tape.L = {tp.L:g} m)"
            )
        self.move = self.element * max(1, math.ceil(self.window.move / self.element - 1e-9))
        self.predictor = choose_predictor(config.coiling.predictor, self.element, config.hub.radius)
        # the full shell's largest steps for its predictor, unless coiling.max_step sets one
        self.max_step = self.max_step or config.coiling.max_step or CoilingRun.max_steps[self.predictor]
        self.frame = HubFrame(config.hub.radius, tp.h, config.coiling.sense)
        # [solver] and [coiling] petsc_options override the linear solve the contact needs
        self.petsc_options = {
            **linear_solver_options(cc.turns == "surface"),
            **config.solver.petsc_options,
            **config.coiling.petsc_options,
        }
        self.centroid = BeamSection.arc_centroid_depth(tp.R, tp.alpha)
        self.contact = ContactSettings.from_config(config, self.element)
        self.angle = 0.0
        self.pull = config.coiling.tension  # [N] at the free end (a payout may set its own)
        self.records: list[CoilingRecord] = []
        self._root_loads = None  # (the hybrid, its root's loads), made when first read
        self.moves: list[tuple[float, float, float]] = []
        self._next_step = self.first_step
        self._leg: tuple[float, float] | None = None  # the leg being turned: its end and largest step
        if restart is not None:
            self.restore(restart, tables)
        else:
            self.hybrid = self._build(0.0)
            self.moves.append((0.0, *self._ends(0.0)))

    def _ends(self, start: float) -> tuple[float, float]:
        return start, min(start + self.window_length, self.config.tape.L)

    def _build(self, start: float) -> HybridProblem:
        return self.build(start, f"hybrid_coil{len(self.moves)}")

    def build(
        self, start: float, name: str, released: bool = False, end: float | None = None
    ) -> HybridProblem:
        """A hybrid of this coiling's tape, hub and settings with its window from ``start`` [m]
        along the tape (to ``end`` [m], by default the window's length on), in its reference
        state; PETSc options under ``name + "_"``. ``released``: the free end let go (a
        deploying tape's): no guide and no pull there."""
        config, frame, tp = self.config, self.frame, self.config.tape
        start, end = self._ends(start) if end is None else (start, end)
        shell = WindowOnHub(
            config,
            start,
            end - start,
            self.element,
            frame,
            self.contact,
            shift=self.predictor == "shift" and not released,
            released=released,
            pull=self.pull,
            comm=self.comm,
            name=f"{name}_shell",
        )
        spans = ([(0.0, start)] if start > 0 else []) + ([(end, tp.L)] if end < tp.L else [])
        beam = tape_beam(
            config,
            spans,
            self.element,
            flat_before=start,
            edge_relief=True,
            comm=self.comm,
            name=f"{name}_beam",
        )
        ties = []
        if start > 0:
            # the root on the hub: the flattened strip's line lies on the hub's top generator
            beam.clamp((0.0, 0.0, self.centroid), turning_about=(frame.axis_point, frame.axis), at=(0, 0, 0))
            c = self.contact
            if c.turns == "spiral":

                def obstacle(psi):
                    return spiral_obstacle(psi, frame.radius, tp.h, c.max_turns, c.ramp_width) + tp.h / 2

            else:  # the hub and the fairing behind the root; the turns' contact is the surfaces'

                def obstacle(psi):
                    return root_fairing(psi, frame.radius, tp.h, c.ramp_width) + tp.h / 2

            beam.winding_contact(
                frame.axis_point,
                frame.axis,
                -frame.axis_point,
                obstacle,
                c.penalty * tp.b,
                c.smoothing,
                # across its width, the flattened strip rests as the shell's does: a line
                # alone lets the coil's section twist, and the sections that a window move
                # places from it dig their edges into the turn beneath (docs/notes/hybrid.md)
                half_width=(
                    (lambda x: np.where(x < start, tp.b / 2, 0.0))
                    if self.window.beam_contact == "width"
                    else None
                ),
            )
            ties.append(("xi1_min", (start, 0.0, self.centroid), "flat"))
        if end < tp.L:
            ties.append(("xi1_max", (end, 0.0, self.centroid), "arc"))
        if end < tp.L and not released:
            tip = (tp.L, 0.0, self.centroid)
            # held in the plane of coiling, free to turn in it: the full shell's guide holds the
            # end's directors, but its reduced-integrated shear lets the end section pitch within
            # the last element; with the pitch held the hybrid's free part stood higher and its
            # tape left the coil early (docs/notes/hybrid.md, the free end)
            beam.hold(tip, (1, 2), rotation=(0, 2))
            beam.end_load(tip, force=(self.pull, 0.0, 0.0), constant=True)
            if self.predictor == "shift":
                # the straight part beyond the window runs towards the hub as the tape winds on
                beam.slide(end - 1e-9 * tp.L, lambda a, b: wound_length(shell.contact, a, b))
        return HybridProblem(
            shell,
            beam,
            ties=ties,
            modulus=tp.E,
            penalty=self.window.tie_penalty,
            name=name,
            contact=self._turn_contact(shell, beam, start),
        )

    def _turn_contact(self, shell, beam, start: float) -> TurnContact | None:
        """The turns' real contact of a hybrid with its window from ``start`` [m]: the window's
        shell and the strip of the flattened beam behind it, one surface (None on the spiral
        obstacle, whose contact is in each part's energy)."""
        c, tp = self.contact, self.config.tape
        if c.turns == "spiral":
            return None
        parts = [ShellSurface(shell.model, shell.contact.nodes, block=0)]
        mesh = beam.mesh
        owned = np.arange(mesh.topology.index_map(1).size_local, dtype=np.int32)
        middle = dolfinx.mesh.compute_midpoints(mesh, 1, owned)[:, 0]
        flat = owned[middle < start]
        if self.comm.allreduce(len(flat)) > 0:
            across = np.array([[0.0, -tp.b / 2, 0.0], [0.0, 0.0, 0.0], [0.0, tp.b / 2, 0.0]])
            parts.append(BeamStripSurface(beam.model, flat, across, block=1))
        return TurnContact(JoinedSurface(parts), self.frame, tp.h, c.penalty, c.smoothing, c.buffer)

    # -- measures ------------------------------------------------------------------------------
    def dofs(self) -> int:
        """The hybrid's unknowns: its shell's and its beam's (collective)."""
        return global_size(self.hybrid.shell.model.W) + global_size(self.hybrid.beam.model.W)

    def strain_energy(self) -> float:
        """The strain energy of shell and beam [J] (the ties' penalty energy apart; collective)."""
        return self.hybrid.shell.strain_energy() + self.hybrid.beam.model.strain_energy()

    def coil_geometry(self) -> dict[str, float]:
        """The coiled length [m], the material behind the lift-off (the point wound by the hub
        angle), and the outer coil radius [m], that of the outer face half a turn behind it, as
        the full shell's (:func:`~tapecoil.measures.centre_line.coil_geometry`; collective)."""
        x, points = centre_line(self.hybrid)
        psi = np.maximum.accumulate(winding_along(self.frame, self.angle, points))
        radius = self.frame.polar(points.T)[0]
        probe = self.angle - math.pi if self.angle > math.pi else self.angle
        return {
            "coiled_length": float(np.interp(self.angle, psi, x)),
            "outer_radius": float(np.interp(probe, psi, radius)) + 0.5 * self.config.tape.h,
        }

    def lift_off(self) -> float:
        """Where along the tape [m] it leaves the coil: the coiled length (collective)."""
        return self.coil_geometry()["coiled_length"]

    def root_tension(self) -> float:
        """The axial force N [N] the tape carries into its root on the hub (tension positive): the
        beam's internal force at its clamped root along the tape's direction there, turned with
        the hub (as the full shell's :meth:`CoilingProblem.edge_forces`), or the window's when it
        holds the root (collective). T - N is the coiling tension of the first turn."""
        h = self.hybrid
        if h.shell.root is not None:
            f = h.shell.root_force()
        else:
            f = h.beam.internal_force((0.0, 0.0, self.centroid))
        return -float(f @ self.frame.tangent(self.angle))

    def outer_turn_tension(self) -> dict | None:
        """The coiling tension T - N of the turn being wound, N read across the section at the
        full shell's station (:func:`~tapecoil.measures.payout.outer_station`, 1 to 3 rad behind
        the lift-off, clear of the climb over the root): from the window's strain energy
        (:class:`~tapecoil.measures.section_forces.SectionForces`) where the station lies in the
        window, else from the beam's axial force there; with the station's winding behind the
        lift-off [rad], its place along the tape [m] and its distance from the axis [m]. None
        before the coil has a station (collective)."""
        if self.angle < OUTER_STATION[0] + STATION_MARGIN:
            return None
        h = self.hybrid
        x, points = centre_line(h)
        psi = np.maximum.accumulate(winding_along(self.frame, self.angle, points))
        behind = outer_station(self.angle)
        station = float(np.interp(self.angle - behind, psi, x))
        start, end = h.shell.surface.xi_range[0]
        if start < station < end:
            forces = h.shell.section_forces()
            k = int(np.argmin(np.abs(forces["xi1"] - station)))
            where, N = float(forces["xi1"][k]), float(forces["axial_force"][k])
        else:
            points_q, N_q = h.beam.axial_force()
            k = int(np.argmin(np.abs(points_q[:, 0] - station)))
            where, N = float(points_q[k, 0]), float(N_q[k])
        radius = float(
            self.frame.polar(np.array([np.interp(where, x, points[:, i]) for i in range(3)])[:, None])[0][0]
        )
        return {
            "station": where,
            "station_winding": behind,
            "outer_turn_radius": radius,
            "coiling_tension_outer": self.pull - N,
        }

    def hub_torque(self) -> float:
        """The torque [N m] the hub applies to the tape through the root's attachment, positive in
        the coiling sense: the reaction of the beam's clamped root node, or of the window's root
        edge when it holds the root, at the converged state (as the full shell's
        :meth:`~tapecoil.phases.coiling.CoilingProblem.hub_torque`; collective)."""
        if self._root_loads is None or self._root_loads[0] is not self.hybrid:
            self._root_loads = (self.hybrid, HybridRootLoads.at_rest(self.hybrid, self.frame))
        return -self._root_loads[1]()["root_torque"]

    def wrap_axial_force(self) -> tuple[float, float]:
        """The axial force N [N] of the flattened beam on the first turn, mean and spread (max -
        min) over its quadrature points short of the turn's climb over the root and of the
        window (collective; nan while the window holds the root). With frictionless contact N is
        uniform there, and T - N is the coiling tension of the first turn; a coarse beam on the
        hub scatters it from point to point (the contact's line load between its nodes)."""
        start = self.hybrid.shell.surface.xi_range[0][0]
        rho = self.config.hub.radius + self.config.tape.h / 2
        first_turn = rho * (2 * math.pi - self.contact.ramp_width)
        x, N = self.hybrid.beam.axial_force()
        pick = x[:, 0] < min(start, first_turn)
        if not pick.any():
            return math.nan, math.nan
        return float(N[pick].mean()), float(np.ptp(N[pick]))

    # -- stepping -------------------------------------------------------------------------------
    def _record(self, step) -> None:
        self.angle = float(step.load)
        self._next_step = abs(float(step.next_step or step.step))  # forwards or back
        self.records.append(
            CoilingRecord(
                self.angle,
                float(step.step),
                self._ends(self.hybrid.shell.surface.xi_range[0][0]),
                self.lift_off(),
                self.strain_energy(),
                int(step.iterations),
                time.perf_counter() - self._t0,
            )
        )

    def flatten(self) -> list:
        """Flatten the root onto the hub (``coiling.flatten_steps`` steps), the pull held;
        returns the steps' records (:class:`~tapecoil.core.stepping.StepRecord`)."""
        self._t0 = time.perf_counter()
        h = self.hybrid
        steps = self.config.coiling.flatten_steps
        h.shell.flattening = True
        records = h.solve(
            1.0,
            first_step=1.0 / steps,
            max_step=1.0 / steps,
            solver_config=self.config.solver,
            options=self.petsc_options,
        )
        h.shell.flattening = False
        h.beam.committed_load = 0.0
        h.set_load(0.0)
        return records

    def coil(self, final_angle: float, on_step=None, stops: tuple[float, ...] = ()) -> None:
        """Turn the hub from where it is to ``final_angle`` [rad], forwards (coiling) or back (a
        driven hub's payout), the window moved with the lift-off, landing exactly on every hub
        angle in ``stops`` [rad] on the way (as the full shell's
        :meth:`~tapecoil.phases.coiling_run.CoilingRun.coil`); ``on_step(record)`` after each
        converged step (collective)."""
        if not hasattr(self, "_t0"):
            self._t0 = time.perf_counter()
        tp = self.config.tape
        rho = self.config.hub.radius + tp.h / 2
        bending = self.config.wall.bending
        while abs(final_angle - self.angle) > 1e-12:
            back = final_angle < self.angle
            if self._leg is not None and abs(self._leg[0] - self.angle) <= 1e-12:
                self._leg = None  # stopped on its last step: a restart takes the next leg
            if self._leg is None:
                # moved before a solve, never after: the state a call leaves is a converged one
                if back:
                    self._move_window_back()
                    # the lift-off runs down the coil by its own radius per radian: a leg lets
                    # it travel no further than a move, so the shell keeps `behind` of coil
                    turn = self.move / self.coil_geometry()["outer_radius"]
                    between = [a for a in stops if final_angle < a < self.angle - 1e-12]
                    target = max([final_angle, self.angle - turn, *between])
                else:
                    self._move_window()
                    ahead = [a for a in stops if self.angle + 1e-12 < a < final_angle]
                    target = min([final_angle, self.angle + self.move / rho, *ahead])
                self._leg = (target, min(self.max_step, abs(target - self.angle)))
            # a leg is the hub's turn between window moves, its largest step set at its start (a
            # restarted run goes on with the leg it stopped in, as it would have)
            target, leg_step = self._leg
            first = min(self._next_step, abs(target - self.angle))

            def record(step):
                self._record(step)
                if on_step is not None:
                    on_step(self.records[-1])

            self.hybrid.solve(
                target,
                first_step=first,
                max_step=leg_step,
                min_step=1e-6,
                relaxation=relaxation_scale(bending, self.element),
                on_step=record,
                solver_config=self.config.solver,
                options=self.petsc_options,
                easy_iterations=EASY_ITERATIONS,
            )
            self.angle = target
            self._leg = None

    # -- restart -------------------------------------------------------------------------------
    def restart_state(self) -> dict:
        """What, beside its hybrid's tables (:meth:`HybridProblem.state_tables`), this coiling
        needs to go on from its last converged step as if never stopped (JSON-ready)."""
        return {
            "hub_angle": self.angle,
            "pull": self.pull,
            "next_step": self._next_step,
            "moves": [list(move) for move in self.moves],
            "leg": None if self._leg is None else list(self._leg),
            "records": [dataclasses.asdict(record) for record in self.records],
        }

    def restore(self, state: dict, tables: dict) -> None:
        """Go on from :meth:`restart_state` and the tables of its hybrid: the window built again
        where it was (its PETSc prefix the same) and its state put back (collective)."""
        self.moves = [tuple(move) for move in state["moves"]]
        self.records = [CoilingRecord(**{**r, "window": tuple(r["window"])}) for r in state["records"]]
        self.angle = float(state["hub_angle"])
        self.pull = float(state.get("pull", self.config.coiling.tension))
        self._next_step = float(state["next_step"])
        self._leg = None if state["leg"] is None else tuple(state["leg"])
        self.hybrid = self.build(self.moves[-1][1], f"hybrid_coil{len(self.moves) - 1}")
        self.hybrid.set_state(tables)
        self._t0 = clock_origin(last_wall_time(self.records))

    def carry_into(self, model, hybrid: HybridProblem | None = None, angle: float | None = None) -> None:
        """Set the full shell of ``model`` (a :class:`~tapecoil.phases.coiling.CoilingProblem` of
        the same configuration) to this hybrid's state (or ``hybrid``'s: one of this tape at this
        hub angle, or at the hub angle ``angle`` [rad], a deploying one): the hub angle and the
        pull, the shell's state where the window is and the beams' sections placed elsewhere
        (:func:`~tapecoil.models.window.carry_over`), and the winding angles (collective). The
        full shell is then in the hybrid's configuration, not in its own equilibrium."""
        hybrid = hybrid or self.hybrid
        angle = self.angle if angle is None else angle
        x, psi = self._winding_along_line(hybrid, angle)
        model.set_hub_angle(angle)
        model.tension.value = self.pull
        carry_over(hybrid, full_shell(model.model))
        self._set_shell_winding(model.contact, x, psi, angle)

    def carry_winding(self, old: HybridProblem, new: HybridProblem, angle: float | None = None) -> None:
        """The winding angles of ``new``'s beam and shell (a hybrid ``old``'s state was carried
        into) from ``old``'s centre line at this coiling's hub angle, or at ``angle`` [rad]
        (collective)."""
        angle = self.angle if angle is None else angle
        x, psi = self._winding_along_line(old, angle)
        new.beam.set_winding(lambda s: np.interp(s, x, psi))
        self._set_shell_winding(new.shell.contact, x, psi, angle)

    def _winding_along_line(self, hybrid: HybridProblem, angle: float) -> tuple[np.ndarray, np.ndarray]:
        """The places [m] along ``hybrid``'s centre line and their winding angles [rad] at the hub
        angle ``angle`` (collective)."""
        x, points = centre_line(hybrid)
        return x, winding_along(self.frame, angle, points)

    @staticmethod
    def _set_shell_winding(contact, x: np.ndarray, psi: np.ndarray, angle: float) -> None:
        contact.psi.x.array[:] = np.interp(contact.nodes.xi[0], x, psi)
        contact.update(angle)

    def _move_window(self) -> None:
        tp = self.config.tape
        start, end = self._ends(self.hybrid.shell.surface.xi_range[0][0])
        if end >= tp.L:
            return  # at the free end: the window stays
        lift = self.lift_off()
        wanted = self.element * math.floor((lift - self.window.behind) / self.element + 1e-9)
        if wanted < start + self.move - 1e-9 * tp.L:
            return
        new_start = min(wanted, tp.L - self.window_length)
        if new_start <= start:
            return
        self._adopt(self._carried(new_start), new_start)

    def _carried(self, start: float) -> HybridProblem:
        """A new hybrid with its window from ``start`` [m] (and this coiling's pull), this one's
        state and winding angles carried into it (collective)."""
        new = self._build(start)
        carry_over(self.hybrid, new)
        self.carry_winding(self.hybrid, new)
        return new

    def _adopt(self, new: HybridProblem, start: float) -> None:
        """Go on with ``new``, its window from ``start`` [m], recorded among the moves."""
        self.hybrid = new
        self.moves.append((self.angle, *self._ends(start)))

    def start_back(self, lift: float, start: float, reach: float = 0.0) -> float | None:
        """The new start [m], nearer the root, of a window starting at ``start`` [m] for the
        lift-off at ``lift`` [m] running down the coil (a deployment, a payout), None to stay:
        once the lift-off has come within ``behind + reach`` of the start (``reach``: how far it
        may run before the next look), ``behind + move`` behind it (on the elements' grid), so
        that at least ``behind`` of the coil is always shell, as when coiling."""
        near = self.window.behind + reach - 1e-9 * self.config.tape.L
        if start <= 0.0 or lift - start >= near:
            return None
        wanted = self.element * math.floor((lift - self.window.behind - self.move) / self.element + 1e-9)
        return max(min(wanted, start - self.element), 0.0)

    def _move_window_back(self) -> None:
        """The window moved towards the root as the hub turns back (the flattened beam on the
        coil becomes shell, the shell beyond the window's new end arc beam), the sections placed
        from the beam settled on the coil (:func:`~tapecoil.models.window_settling.settle_placed`);
        a settling that fails stops with the last converged state (collective)."""
        # looked at once a leg, over which the lift-off runs down by up to a move
        start = self.hybrid.shell.surface.xi_range[0][0]
        new_start = self.start_back(self.lift_off(), start, reach=self.move)
        if new_start is None:
            return
        old_window = self.hybrid.shell.surface.xi_range[0]
        new = self._carried(new_start)
        settling = settle_placed(new, old_window, self.config)
        if not settling["converged"]:
            raise ContinuationError(
                f"the hybrid's window moved back to {new_start:.4g} m at {self.angle:.6g} rad: the "
                f"sections placed from the flattened beam did not settle on the coil "
                f"({settling['iterations']} Newton iterations); use the full shell "
                f"(model.kind = 'shell'). Last converged hub angle {self.angle:.6g} rad",
                self.angle,
            )
        self._adopt(new, new_start)

    def set_pull(self, pull: float) -> None:
        """Pull the free end with ``pull`` [N] from the next step on: the hybrid built again on
        its window with that pull and its state carried over node by node (collective)."""
        if pull == self.pull:
            return
        self.pull = float(pull)
        start = self.hybrid.shell.surface.xi_range[0][0]
        self._adopt(self._carried(start), start)
