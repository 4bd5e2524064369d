"""What a step of the deployment measured: its history row, and the energy account it closes.

The model has no physical damping, so what the stowed energy and the release's work do not
account for in strain, contact and kinetic energy is what the computation lost. Two parts of it
are not the time integration: the converged residual's work (the Newton tolerance) and the
contact energy the update of the winding angles adds between steps (the obstacle between the
turns follows them). With friction on the hub, what its springs hold is potential energy and
what its slip dissipates since release is taken out of the remainder before it. With F(q) = r
the residual of a step, inertia and averaged forces times the step give the kinetic and
potential energies' change plus the scheme's dissipation D, so

    stowed + work - potential - kinetic = sum (D - r . dq - update's change),

and the scheme's own dissipation is the remainder plus the residual's work plus the
updates'. :class:`DeploymentRows` keeps these accounts from step to step.
"""

from __future__ import annotations

from tapecoil.core.stepping import StepRecord


class DeploymentRows:
    """The rows of a :class:`~tapecoil.phases.deployment.DeploymentProblem`'s history.

    ``stowed_energy`` is the potential (strain and contact) of the first row, ``external_work``
    the work of the loads so far (the releasing hold, gravity); both go into a restart state
    (:meth:`restart_state`).
    """

    def __init__(self, model):
        self.m = model
        self.stowed_energy = None
        self.external_work = 0.0
        self.residual_work = 0.0
        self.update_energy = 0.0
        self.friction_at_release = None  # [J] what the hub's friction had dissipated by then

    def restart_state(self) -> dict:
        return {
            "external_work": self.external_work,
            "stowed_energy": self.stowed_energy,
            "residual_work": self.residual_work,
            "update_energy": self.update_energy,
            "friction_at_release": self.friction_at_release,
        }

    def restore(self, state: dict) -> None:
        self.external_work = state["external_work"]
        self.stowed_energy = state["stowed_energy"]
        # checkpoints written before these accounts were kept start them at the restart
        self.residual_work = state.get("residual_work", 0.0)
        self.update_energy = state.get("update_energy", 0.0)
        self.friction_at_release = state.get("friction_at_release")

    def add_step_work(self) -> None:
        """The loads' and the converged residual's work over the step just solved (the hold,
        gravity; before the model advances)."""
        self.external_work += self.m.step_work()
        self.residual_work += self.m.residual_work()

    def add_update_energy(self, change: float) -> None:
        """The contact energy's change by the update after a step (:meth:`DeploymentProblem.update`)."""
        self.update_energy += change

    def row(self, t: float, step: StepRecord | None) -> dict:
        """The row of the state at time ``t`` reached by ``step`` (None: the release), without
        its wall time."""
        m = self.m
        e = m.energies()
        potential = e["strain"] + e["contact"] + e["friction"]
        if self.stowed_energy is None:
            self.stowed_energy = potential
        if self.friction_at_release is None:
            self.friction_at_release = e["friction_dissipated"]
        friction = e["friction_dissipated"] - self.friction_at_release
        lift = m.lift_off()
        tip = m.tip()
        dissipated = self.stowed_energy + self.external_work - potential - e["kinetic"] - friction
        return {
            "time": t,
            "step": step.step if step else 0.0,
            "newton_iterations": step.iterations if step else 0,
            "cutbacks": step.cutbacks if step else 0,
            # the step's local error over its tolerance (0 without error control), and the
            # converged attempts rejected as inaccurate before it
            "step_error": step.error if step and step.error is not None else 0.0,
            "rejected_steps": step.rejected if step else 0,
            "lambda": lift["lambda"],
            "coiled_length": lift["coiled_length"],
            # how loose the coil is: the largest gap between a turn and the one beneath it behind
            # the lift-off [m] and where [m], the turns still wound beyond the lift-off
            "coil_opening": lift["coil_opening"],
            "coil_opening_at": lift["coil_opening_at"],
            "loose_turns": lift["loose_turns"],
            "kinetic_energy": e["kinetic"],
            "strain_energy": e["strain"],
            "membrane_energy": e["membrane"],
            "bending_energy": e["bending"],
            "shear_energy": e["shear"],
            "contact_energy": e["contact"],
            # the hub's friction: its sticking springs' energy, and what its slip has dissipated
            "friction_energy": e["friction"],
            "friction_dissipated": friction,
            # the work of the loads: the releasing hold on the free end, and gravity
            "external_work": self.external_work,
            # what the energy balance misses (no physical damping but the hub's friction): the
            # time integration's dissipation, less the residual's work and the contact updates'
            "dissipated_energy": dissipated,
            "residual_work": self.residual_work,
            "contact_update_energy": self.update_energy,
            # the scheme's own numerical dissipation
            "scheme_dissipation": dissipated + self.residual_work + self.update_energy,
            # the hub: its angle [rad] and rate [rad/s] (coiling sense), its kinetic energy (in
            # kinetic_energy too), and the angular momentum of tape and hub about its axis
            "hub_angle": m.hub_angle,
            "hub_rate": 0.0 if m.rotor is None else m.rotor.rate,
            "hub_kinetic_energy": e["hub_kinetic"],
            "angular_momentum": m.angular_momentum(),
            "tip_x": tip[0],
            "tip_y": tip[1],
            "tip_z": tip[2],
            "max_penetration": m.tape.max_penetration(),
            # the force [N] and moment [N m] the tape exerts on the hub through its root
            **m.root_loads(),
        }
