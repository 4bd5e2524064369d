"""The tension a hub needs, in every coiling regime: a tape wrapped round it and pulled tight.

After the protocol of Wilson et al. (2020) (physics brief Sec. 10): the tape is attached to the
cylinder at one end and its free end is pulled under displacement control; the force-extension
curve is traced through the formation and the splitting of localised folds, and the tension the
hub needs is the force at which the centre line first conforms to the cylinder, within three
thicknesses, over a wrap of 305 degrees (:mod:`tapecoil.measures.wrap`).

Wilson et al. seed two folds with temporary cylinders. Here the folds come from the mechanics:

1. **Wrap.** The root, clamped to the hub, is flattened onto it and the hub turns by
   ``wrap_angle`` while the free end, on the guide line, is pulled by a dead load (the pull of the
   coiling phase: a fraction of Eq. 2.9, or more than Eq. 2.6, at the mid-surface radius).
2. **Release.** The hub stops; the free end's displacement along the guide becomes the control
   and is let back towards the hub by ``release``. The wrapped tape gives up what it no longer
   holds: on a hub larger than the tape's own radius it forms localised folds off the cylinder
   (thesis Fig. 2.5b); on a smaller one the whole coil loosens off the hub.
3. **Pull.** The end is pulled again until the centre line conforms over ``conform_angle``:
   the folds shrink, merge and vanish, or the loosened coil closes on the hub. The force then is
   the required tension.

The end's displacement is prescribed on every node of the end (its section keeps the shape it
had at the release), and the force is the reaction there, the internal force along the guide.
Through the snaps of the folds the continuation falls back on pseudo-transient relaxation.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import Config, ConfigError
from tapecoil.core.dofs import global_size
from tapecoil.core.stepping import ContinuationError
from tapecoil.geometry.meshes import FREE_END
from tapecoil.measures.centre_line import edge_lines
from tapecoil.measures.wrap import wrap_measure
from tapecoil.models.edges import facet_condition
from tapecoil.phases.coiling import CoilingProblem
from tapecoil.phases.coiling_run import CoilingRun


@dataclass(frozen=True)
class WrapStudy:
    """How the wrapping is done and read (see the module).

    Attributes:
        wrap_angle: hub rotation that wraps the tape [deg]; past ``conform_angle`` by the
            lift-off's span.
        free_length: tape beyond the wrapped length r_c wrap_angle [m].
        wrap_step: the largest hub-angle step of the wrap [rad].
        wrap_pull: the pull while the hub turns, as a fraction of Eq. 2.9 at the mid-surface
            radius [-], or ``bending_margin`` times Eq. 2.6 if that is more (with ``min_pull``
            [N] as a floor).
        bending_margin: the pull while the hub turns over Eq. 2.6 at the mid-surface radius,
            at least [-]: under Eq. 2.6 a hub smaller than the tape's radius wraps it loosely.
        min_pull: the smallest pull while the hub turns [N].
        release: how far the free end is let back towards the hub [m].
        overpull: how far past its position at the end of the wrap the end may be pulled [m]
            before the study gives up on conformity.
        tolerance: the conformity band [thicknesses].
        conform_angle: the wrap over which the centre line must conform [deg].
        element_size: element length along the tape [m]; at most a twenty-fourth of the hub's
            circumference is used, so that small hubs are resolved too.
        elements_across: elements across the width [-].
        max_step: the largest step of the end's motion, as a fraction of ``release`` [-].
    """

    wrap_angle: float = 340.0
    free_length: float = 0.1
    wrap_step: float = 0.2
    wrap_pull: float = 0.5
    bending_margin: float = 1.3
    min_pull: float = 0.2
    release: float = 0.005
    overpull: float = 0.002
    tolerance: float = 3.0
    conform_angle: float = 305.0
    element_size: float = 0.004
    elements_across: int = 6
    max_step: float = 0.02

    def check(self) -> None:
        """Refuse options that cannot give a reading, naming the key (``sweep.wrapping.*``)."""
        bad = [
            f"{f.name} = {getattr(self, f.name)!r}: must be a number"
            for f in dataclasses.fields(self)
            if isinstance(getattr(self, f.name), bool) or not isinstance(getattr(self, f.name), int | float)
        ]
        if bad:  # the ranges below cannot be compared
            raise ConfigError("sweep.wrapping: " + "; ".join(bad))
        if not 0 < self.conform_angle < self.wrap_angle <= 720:
            bad.append("conform_angle and wrap_angle: need 0 < conform_angle < wrap_angle <= 720 deg")
        for key in (
            "free_length",
            "wrap_step",
            "wrap_pull",
            "bending_margin",
            "release",
            "overpull",
            "tolerance",
            "element_size",
            "max_step",
        ):
            if not getattr(self, key) > 0:
                bad.append(f"{key} = {getattr(self, key)!r}: must be positive")
        if self.min_pull < 0:
            bad.append(f"min_pull = {self.min_pull!r}: must not be negative")
        if self.elements_across < 2:
            bad.append(f"elements_across = {self.elements_across!r}: at least 2")
        if bad:
            raise ConfigError("sweep.wrapping: " + "; ".join(bad))


class EndDisplacement:
    """The free end's displacement along the guide (+x) prescribed: the end held at its position
    ``u_x0`` (per node, at the moment of the switch) plus ``d``."""

    def __init__(self, model: CoilingProblem):
        self.value, self.bc = facet_condition(model.model, (0, 0), model.strip.facet_tags.find(FREE_END))
        self.start = model.model.q.sub(0).sub(0).collapse().x.array.copy()
        self.value.x.array[:] = self.start
        model.solver.bcs.append(self.bc)
        # the dead load no longer acts: the reaction holds the end
        model.tension.value = 0.0

    def set(self, d: float) -> None:
        self.value.x.array[:] = self.start + d


def wrap_case(config: Config, study: WrapStudy, extra_length: float = 0.0) -> Config:
    """The configuration the study wraps: the tape ``r_c wrap_angle + free_length`` long (plus
    ``extra_length`` [m]), the hub turned by ``wrap_angle`` under the study's pull, the study's
    mesh (see :class:`WrapStudy`)."""
    tp, r_c, bending = config.tape, config.hub.radius, config.wall.bending
    rho = r_c + tp.h / 2
    eq_2_6 = theory.coiling_tension_bending(bending, tp.alpha, tp.R, rho)
    eq_2_9 = theory.coiling_tension_tension_dominated(bending, tp.alpha, tp.R, rho)
    wrap = math.radians(study.wrap_angle)
    pull = max(study.min_pull, study.wrap_pull * eq_2_9, study.bending_margin * eq_2_6)
    return dataclasses.replace(
        config,
        tape=dataclasses.replace(tp, L=r_c * wrap + study.free_length + extra_length),
        coiling=dataclasses.replace(config.coiling, hub_angle=wrap, tension=pull),
        mesh=dataclasses.replace(
            config.mesh,
            element_size=min(study.element_size, 2 * math.pi * r_c / 24),
            elements_across=study.elements_across,
        ),
    )


def wrap_reading(model: CoilingProblem, wrap: float, tolerance: float) -> dict:
    """The wrap's conformity, folds and section rise at the current state, the hub at ``wrap``
    [rad], within ``tolerance`` thicknesses (:func:`~tapecoil.measures.wrap.wrap_measure`;
    collective). The winding angles are read from the state first: an end's motion draws
    material round the hub."""
    tape, h = model.tape, model.config.tape.h
    model.contact.update(wrap)
    line = tape.centre_line()
    edges = [(e["xi1"], e["radius"]) for e in edge_lines(tape)]
    rho = tape.r_hub + h / 2
    return wrap_measure(line["psi"], line["radius"], rho, h, wrap, tolerance, line["xi1"], edges)


class _Conformed(Exception):
    """The centre line conforms: the pull has found what it was looking for."""


def wrapping_tension(config: Config, comm=MPI.COMM_WORLD, study: WrapStudy | None = None) -> dict:
    """The tension the configured hub needs, by wrapping the configured tape round it (module doc).

    Returns the force-extension history (a row per converged step: phase, end displacement d,
    force, the root's axial force, conforming wrap, folds and their radii), the required tension
    (None if the pull did not make the tape conform) and the lift-off tension (the required
    tension less the axial force the clamped root holds then), the largest number of folds and
    their radii, and Eq. 2.6 and Eq. 2.9 at the mid-surface radius.
    """
    study = study or WrapStudy()
    study.check()
    tp, r_c, bending = config.tape, config.hub.radius, config.wall.bending
    rho = r_c + tp.h / 2
    eq_2_6 = theory.coiling_tension_bending(bending, tp.alpha, tp.R, rho)
    eq_2_9 = theory.coiling_tension_tension_dominated(bending, tp.alpha, tp.R, rho)
    wrap = math.radians(study.wrap_angle)
    case = wrap_case(config, study)
    pull = case.coiling.tension
    t0 = time.perf_counter()
    model = CoilingProblem(case, comm)
    run = CoilingRun(model, max_step=study.wrap_step)
    history: list[dict] = []

    def measure(phase: str, d: float, iterations: int) -> dict:
        reading = wrap_reading(model, wrap, study.tolerance)
        forces = model.edge_forces()
        row = {
            "phase": phase,
            "end_displacement": d,
            "force": forces["tension"],
            "root_tension": forces["root_tension"],
            **reading,
            "newton_iterations": iterations,
            "wall_time": time.perf_counter() - t0,
        }
        history.append(row)
        return row

    message, required, fold_state, fold_state_at = "", None, None, None
    try:
        run.flatten()
        run.coil(wrap)
    except ContinuationError as err:
        message = f"the wrap stopped: {err}"
    if not message:
        end = EndDisplacement(model)
        measure("wrapped", 0.0, 0)
        control = model.config.solver.control(
            initial_step=study.max_step, max_step=study.max_step, min_step=1e-7
        )
        release_folds = -1  # the most folds seen in the release: its state is pictured

        def released(step):
            nonlocal release_folds, fold_state, fold_state_at
            row = measure("release", step.load, step.iterations)
            if row["folds"] > release_folds:
                release_folds = row["folds"]
                fold_state, fold_state_at = model.model.q.x.array.copy(), step.load

        cont = run.continuation(end.set, control)
        cont.on_step = released
        start = -study.release
        try:
            cont.run(0.0, -study.release)
        except ContinuationError as err:
            start = err.load
            message = f"the release stopped at d = {err.load:.4g} m: {err}"

        def pulled(step):
            row = measure("pull", step.load, step.iterations)
            if row["conforming_wrap_deg"] >= study.conform_angle:
                raise _Conformed

        span = study.overpull - start
        control = model.config.solver.control(
            initial_step=study.max_step * study.release / span,
            max_step=study.max_step * study.release / span,
            min_step=1e-7,
        )
        cont = run.continuation(end.set, control)
        cont.on_step = pulled
        try:
            cont.run(start, study.overpull)
            message = message or (
                f"the centre line did not conform over {study.conform_angle:g} deg by an end "
                f"displacement of {study.overpull:g} m"
            )
        except _Conformed:
            required = history[-1]["force"]
        except ContinuationError as err:
            message = f"the pull stopped at d = {err.load:.4g} m: {err}"
    model.solver.destroy()
    wrap_rows = [r for r in run.result.history if r["phase"] == "coil"]
    most_folds = max(history, key=lambda r: r["folds"]) if history else None
    radii = [r for row in history for r in row["fold_radii"]]
    return {
        "ratio": r_c / tp.R,
        "regime": theory.coiling_regime(r_c, tp.R),
        "hub_radius": r_c,
        "mid_surface_radius": rho,
        "wrap_pull": pull,
        "required_tension": required,
        "eq_2_6": eq_2_6,
        "eq_2_9": eq_2_9,
        "max_folds": most_folds["folds"] if most_folds else 0,
        "max_folds_at": most_folds["end_displacement"] if most_folds else None,
        # the force at the end less the axial force the root holds: the configurational tension
        # at the lift-off (Eq. 2.6's quantity, T - N of the coiling phase), when it first conforms
        "lift_off_tension": required - history[-1]["root_tension"] if required is not None else None,
        # how flat the section lies where the centre line conforms, when it first does
        "section_rise": history[-1]["section_rise"] if required is not None else None,
        "fold_radius_min": min(radii) if radii else None,
        "fold_radius_max": max(radii) if radii else None,
        "completed": required is not None,
        "message": message,
        "wrap_steps": len(wrap_rows),
        "wrap_newton_iterations": int(sum(r["newton_iterations"] for r in wrap_rows)),
        "steps": len(history),
        "newton_iterations": int(sum(r["newton_iterations"] for r in history)),
        "dofs": global_size(model.model.W),
        "wall_time": time.perf_counter() - t0,
        "history": history,
        "fold_state": fold_state,
        "fold_state_at": fold_state_at,
        "model": model,
    }
