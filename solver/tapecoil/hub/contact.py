"""Penalty contact of the tape's inner face with the rigid hub and with the turns beneath it.

The hub is a rigid cylinder (axis along y, radius r_hub, placed and turned by a
:class:`~tapecoil.hub.frame.HubFrame`). A tape wound on it is a spiral: the mid-surface of turn
n lies at r_hub + h/2 + n h (physics.md Sec. 2), so the inner face (the mid-surface moved h/2
along the director towards the hub) of a point on turn n must stay outside r_hub + n h, the
outer face of the turn beneath. Rather than searching for the nearest point of the turn below
(general self-contact), every point carries its winding angle psi: the angle it has been carried
round the hub, measured in the hub's rotating frame from the root. psi is updated between load
steps from the converged state and unwrapped continuously (a point never moves by half a turn
in one step), so that points of successive turns, which share a polar angle, keep their turn.
The obstacle radius is then the staircase

    r_obs(psi) = r_hub + h sum_{k>=1} ramp((psi - 2 pi k) / w + 1),

which climbs by h over the last w radians of every turn: there the turn passes over the root
end (and, later, over the step every turn inherits from it). ramp is the C1 smoothstep on
[0, 1]; w is about two elements, so that the climb is resolved.

Penetration g = r_obs - |P - a|_xz > 0 (P the inner-face point, a the axis) costs the penalty
energy k/2 <g>^2 per unit reference area. The bracket <g> is smoothed over a width delta
(delta softplus(g/delta), ``contact.smoothing`` = delta/h, default 1/20): with the plain bracket
Newton cycles as nodes enter and leave contact. Newton iterations (all attempts) on the coarse
benchmark to 6 rad, final step settings: 885 plain, 579 with delta = h/20, 1533 with h/200;
energies equal to 4e-6 and the same largest penetration (0.1 h). The price of h/20: the tape
rests a few delta (5 um) off the coil and, near the lift-off point, that extra support lowers
the coiling tension (the axial-force balance of the coiling module) by about 0.03 N. So the
coiling-tension study uses the plain bracket.

The default stiffness k = E h / (100 l^2) (l the element length along the tape) makes the
contact stiffness of an element, k l^2, one hundredth of the membrane stiffness E h of the
element it pushes on. Measured on the benchmark coarse mesh: with
k l^2 = E h, Newton chattered between contact sets and the run stalled at 3 rad; with E h / 100
it coils the whole 36 rad with the largest penetration about 0.4 h (at the climbs over the root
step, at the end of the run) and typically below 0.1 h; with E h / 10^4 the turns sank by 3 h.
"""

from __future__ import annotations

import math

import dolfinx
import numpy as np
import ufl

from tapecoil.core.smoothing import smoothstep, smoothstep_ufl
from tapecoil.hub.frame import HubFrame
from tapecoil.models.shell import NaghdiShell, Nodes


def default_penalty(E: float, h: float, element_length: float) -> float:
    """Penalty stiffness per unit area [N/m^3]: element contact stiffness E h / 100."""
    return 0.01 * E * h / element_length**2


class CoilContact:
    """Contact of the tape's inner face with the hub and the wound turns (penalty, lagged psi).

    ``frame`` places the hub and gives its radius; ``max_turns`` bounds the number of turns the
    staircase holds; ``ramp_width`` [rad] is w of the module docstring.
    """

    def __init__(
        self,
        model: NaghdiShell,
        frame: HubFrame,
        penalty: float,
        max_turns: int,
        ramp_width: float,
        smoothing: float = 0.0,
    ):
        self.model = model
        self.frame = frame
        self.axis_point = frame.axis_point
        self.r_hub = r_hub = frame.radius
        self.h = h = model.material.h
        # the face in contact, as a multiple of the director: -h/2 (opposite) or +h/2 (equal)
        self.face_offset = 0.5 * h * frame.contact_side
        self.ramp_width = ramp_width
        self.max_turns = max_turns
        self.stiffness = dolfinx.fem.Constant(model.mesh, float(penalty))

        # the winding angle lives on the Q2 nodes of the state: smooth along the tape, and its
        # interpolant resolves the ramps of the staircase
        self.nodes = Nodes(model)
        self.psi = dolfinx.fem.Function(self.nodes.space, name="winding_angle")

        self.smoothing = smoothing
        face = self._face(model.phi, model.d)
        self.radius = ufl.sqrt(face[0] ** 2 + face[2] ** 2)
        steps = sum(
            smoothstep_ufl((self.psi - 2 * math.pi * k) / ramp_width + 1.0) for k in range(1, max_turns + 1)
        )
        self.obstacle = r_hub + h * steps
        self.penetration = self._bracket(self.obstacle - self.radius)
        # the hub carries the first turn up to the start of its climb; beyond, turns carry turns
        self.on_hub = ufl.conditional(ufl.lt(self.psi, 2 * math.pi - ramp_width), 1.0, 0.0)
        density = 0.5 * self.stiffness * self.penetration**2 * model.jacobian
        self.energy = density * model.dx
        self.energy_hub = self.on_hub * density * model.dx
        self.energy_coil = (1.0 - self.on_hub) * density * model.dx
        self.hub_angle = 0.0

    def _face(self, phi, d):
        """The inner face's point relative to the hub axis, for a mid-surface point and director."""
        return phi + self.face_offset * d - ufl.as_vector(self.axis_point)

    def _bracket(self, gap):
        """The penetration <gap>: max(gap, 0), or its smooth version delta softplus(gap / delta)."""
        delta = self.smoothing
        if delta > 0.0:
            x = gap / delta  # written to be stable for either sign
            return delta * (ufl.max_value(x, 0.0) + ufl.ln(1.0 + ufl.exp(-abs(x))))
        return ufl.max_value(gap, 0.0)

    def energy_secant_form(self, q_old, director_variation):
        """Contact virtual work in the direction dq, energy-consistent from q_old to q.

        The penalty energy P(g) = k/2 <g>^2 of a quadrature point depends on the state through
        the gap g = r_obs - rho only, rho = |face|_xz the face point's distance from the axis. Its
        force is written as the secant slope (P(g1) - P(g0)) / (g1 - g0) (the tangent at the mean
        gap when the gap hardly changes) times a variation of g that is exact along the step:
        rho1 - rho0 = (f0 + f1) . (f1 - f0) / (rho0 + rho1) in the xz-plane, with the director
        varied by ``director_variation`` (:meth:`NaghdiShell.director_variation`). Then the work
        along the step is the change of the contact energy (the winding angles, which fix the
        obstacle, are held through a step).
        """
        m = self.model
        _, _, _, d0 = m.kinematics(q_old)
        u0 = ufl.as_vector([q_old[i] for i in range(3)])
        f0, f1 = self._face(m.phi0 + u0, d0), self._face(m.phi, m.d)
        rho0 = ufl.sqrt(f0[0] ** 2 + f0[2] ** 2)
        g0, g1 = self.obstacle - rho0, self.obstacle - self.radius
        k = self.stiffness

        def energy(g):
            return 0.5 * k * self._bracket(g) ** 2

        g_mid = ufl.variable(0.5 * (g0 + g1))
        tangent = ufl.diff(energy(g_mid), g_mid)
        change = g1 - g0
        eps = 1e-6 * self.h  # below it, the secant's round-off would exceed its difference
        secant = (energy(g1) - energy(g0)) / ufl.conditional(ufl.gt(abs(change), eps), change, 1.0)
        slope = ufl.conditional(ufl.gt(abs(change), eps), secant, tangent)
        du = ufl.split(m.dq)[0]
        dface = du + self.face_offset * director_variation
        dg = -((f0[0] + f1[0]) * dface[0] + (f0[2] + f1[2]) * dface[2]) / (rho0 + self.radius)
        return slope * dg * m.jacobian * m.dx

    def obstacle_radius(self, psi: np.ndarray) -> np.ndarray:
        """The staircase r_obs(psi) [m] in numpy (as in the forms)."""
        k = np.arange(1, self.max_turns + 1)[:, None]
        ramps = smoothstep((psi[None, :] - 2 * math.pi * k) / self.ramp_width + 1.0)
        return self.r_hub + self.h * np.sum(ramps, axis=0)

    def polar(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance from the axis and swept angle (:meth:`HubFrame.polar`) of points (3, n)."""
        return self.frame.polar(points)

    def nodal_penetration(self) -> np.ndarray:
        """Penetration r_obs - r [m] of the inner face at this rank's nodes (negative: a gap)."""
        q = self.model.q.x.array
        face = self.nodes.positions(q) + self.face_offset * self.nodes.directors(q)
        return self.obstacle_radius(self.psi.x.array) - self.polar(face)[0]

    def _lab_angles(self) -> np.ndarray:
        return self.polar(self.nodes.positions(self.model.q.x.array))[1]

    def update(self, hub_angle: float) -> None:
        """Winding angles from the current (converged) state at hub angle ``hub_angle`` [rad].

        psi = hub_angle - swept angle: the root sits at the swept angle hub_angle, and material
        behind it in the sense of rotation has been carried round by psi. The branch nearest the
        previous psi is taken: coiled points hardly move in the hub frame.
        """
        raw = hub_angle - self._lab_angles()
        previous = self.psi.x.array
        self.psi.x.array[:] = previous + (raw - previous + math.pi) % (2 * math.pi) - math.pi
        self.hub_angle = hub_angle

    def reset(self) -> None:
        """Winding angles of the reference state (hub angle 0): psi in [0, pi/2) on the flat tape."""
        self.psi.x.array[:] = -self._lab_angles()
        self.hub_angle = 0.0
