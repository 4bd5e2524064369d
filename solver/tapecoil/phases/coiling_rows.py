"""What a converged step of the coiling measured: its history row.

Energies, the forces at the two ends of the tape, the end's slide, the coil's geometry, the
hub torque, measured twice: from the energy balance of the step and as the root's reaction, and
the outer turn's coiling tension read across its sections (:mod:`tapecoil.measures.payout`).
"""

from __future__ import annotations

from tapecoil.core.stepping import StepRecord
from tapecoil.measures.deployment import lift_off
from tapecoil.measures.payout import OUTER_TURN_COLUMNS, outer_turn_tension
from tapecoil.measures.section_forces import SectionForces
from tapecoil.phases.step_stability import StepStability


class CoilingRows:
    """The rows of a :class:`~tapecoil.phases.coiling.CoilingProblem`'s history.

    The hub torque of the energy balance needs the potential of the step before
    (``last_potential``, part of a restart state).
    """

    def __init__(self, model):
        self.m = model
        self.last_potential = None
        self.sections = SectionForces(model.model, model.tape.contact.nodes, model.comm)
        # [solver] stability: each row's state judged (its columns added last)
        self.stability = StepStability(model.solver) if model.config.solver.stability else None

    def row(self, phase: str, load: float, step: StepRecord) -> dict:
        """The row of the state ``step`` reached at ``load`` of ``phase`` ("flatten" or "coil"),
        without its wall time."""
        m = self.m
        angle = m.root.angle
        e = m.tape.energies()
        slide = m.end_slide()
        geometry = m.tape.coil_geometry(angle)
        lam = lift_off(m.tape)["lambda"]
        internal = m.internal_force()  # one assembly for the end forces and the hub torque
        forces = m.edge_forces(internal)
        tension, root_tension = forces["tension"], forces["root_tension"]
        # hub torque from the energy balance of the step: work of the hub = change of stored
        # energy (the hub friction's springs too) + what its slip dissipated + work against the
        # pull (secant over the step). The applied pull, not the measured one: its small noise
        # times the whole slide would swamp a short step
        pull = float(m.tension.value)
        potential = e["strain"] + e["contact"] + e["friction"] + e["friction_dissipated"] - pull * slide
        # undefined (an empty cell) for the first step and across a snap passed by relaxation,
        # where stored energy is released without work of the hub
        torque = ""
        if phase == "coil" and self.last_potential is not None and step.step != 0 and not step.relaxed:
            torque = (potential - self.last_potential) / step.step
        self.last_potential = potential
        outer = (
            outer_turn_tension(m.tape, self.sections, tension, lam, angle)
            if phase == "coil"
            else dict.fromkeys(OUTER_TURN_COLUMNS, "")
        )
        return {
            "phase": phase,
            "load": load,
            "hub_angle": angle,
            "step": step.step,
            "newton_iterations": step.iterations,
            "cutbacks": step.cutbacks,
            "relaxed": int(step.relaxed),
            "hub_torque": torque,
            "hub_torque_reaction": m.hub_torque(internal) if phase == "coil" else "",
            "tension": tension,
            "root_tension": root_tension,
            "coiling_tension": tension - root_tension,
            "end_slide": slide,
            "membrane_energy": e["membrane"],
            "bending_energy": e["bending"],
            "shear_energy": e["shear"],
            "strain_energy": e["strain"],
            "contact_energy_hub": e["contact_hub"],
            "contact_energy_coil": e["contact_coil"],
            "friction_energy": e["friction"],
            "friction_dissipated": e["friction_dissipated"],
            "max_penetration": m.tape.max_penetration(),
            "coiled_length": geometry["coiled_length"],
            "outer_radius": geometry["outer_radius"],
            # the deployed fraction by the deployment's definition (measures.deployment.lift_off)
            "lambda": lam,
            **outer,
            **(self.stability.judge() if self.stability is not None else {}),
        }
