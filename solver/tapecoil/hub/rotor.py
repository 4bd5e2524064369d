"""A hub free to turn on its axis: a rigid rotor of rotary inertia J stepped in time.

The hub's one degree of freedom is its angle zeta [rad] in the coiling sense. Its equation of
motion is J zeta'' = torque of the tape on the hub; the rotor integrates it with the same
generalized-alpha scheme as the tape (the same spectral radius), so that the two are imposed at
the same levels: J a_m + (the tape's residual's torque) = 0, a_m = (1 - alpha_m) a_{n+1} +
alpha_m a_n. The coupling to the tape is :mod:`tapecoil.phases.free_hub`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tapecoil.core.timeint import AlphaParameters, newmark_rates


@dataclass
class HubRotor:
    """The hub's angle, rate and acceleration at the last converged time, and the step's new angle.

    Attributes:
        inertia: rotary inertia J about the axis [kg m^2].
        parameters: the generalized-alpha parameters of the time stepping.
        angle: hub angle zeta_n [rad] (coiling sense), rate [rad/s], acceleration [rad/s^2].
        new_angle: zeta_{n+1} of the step being solved [rad].
    """

    inertia: float
    parameters: AlphaParameters
    angle: float
    rate: float = 0.0
    acceleration: float = 0.0
    new_angle: float = field(init=False)
    dt: float = field(init=False, default=0.0)

    def __post_init__(self):
        if self.inertia < 0:
            raise ValueError(f"the hub's rotary inertia must be >= 0, got {self.inertia} kg m^2")
        self.new_angle = self.angle

    def predict(self, dt: float) -> None:
        """The step's first guess, constant rate (as the tape's, :meth:`GeneralizedAlpha.predict`)."""
        self.dt = dt
        self.new_angle = self.angle + dt * self.rate

    def new_rates(self) -> tuple[float, float]:
        """The rate [rad/s] and angular acceleration [rad/s^2] the step in place ends with, as
        :meth:`advance` will take them (call before it)."""
        return newmark_rates(
            self.parameters, self.dt, self.new_angle, self.angle, self.rate, self.acceleration
        )

    def inertia_torque(self) -> float:
        """J a_m [N m]: the hub's inertia at the generalized-alpha level of the step's new angle."""
        p = self.parameters
        _, a = self.new_rates()
        return self.inertia * ((1 - p.alpha_m) * a + p.alpha_m * self.acceleration)

    def inertia_stiffness(self) -> float:
        """d(J a_m)/d zeta_{n+1} [N m/rad]."""
        p = self.parameters
        return self.inertia * (1 - p.alpha_m) / (p.beta * self.dt**2)

    def advance(self) -> None:
        """After a converged step: the new angle, rate and acceleration become the old."""
        self.rate, self.acceleration = self.new_rates()
        self.angle = self.new_angle

    def kinetic_energy(self) -> float:
        """J zeta'^2 / 2 at the last converged time [J]."""
        return 0.5 * self.inertia * self.rate**2

    def angular_momentum(self) -> float:
        """J zeta' about the axis, in the coiling sense [kg m^2/s]."""
        return self.inertia * self.rate

    def state(self) -> dict:
        """What a restart needs (the converged angle, rate and acceleration)."""
        return {"hub_angle": self.angle, "hub_rate": self.rate, "hub_acceleration": self.acceleration}

    def restore(self, state: dict) -> None:
        self.angle = self.new_angle = state["hub_angle"]
        self.rate, self.acceleration = state["hub_rate"], state["hub_acceleration"]
