"""Penalty contact of the tape's inner face with the rigid hub, and what keeps the turns apart.

The hub is a rigid cylinder (axis along y, radius r_hub, placed and turned by a
:class:`~tapecoil.hub.frame.HubFrame`). Penetration g = r_obs - |P - a|_xz > 0 of the face
towards the hub (P the mid-surface point moved h/2 along the director, a the axis) into an
obstacle of radius r_obs costs the penalty energy k/2 <g>^2 per unit reference area. Two
models keep the turns apart (``contact.turns``):

- ``"spiral"``: the obstacle is the ideal spiral. A tape wound on the hub has the mid-surface
  of turn n at r_hub + h/2 + n h (physics.md Sec. 2), so every point carries its winding angle
  psi (the angle it has been carried round the hub, measured in the hub's rotating frame from
  the root; updated between load steps from the converged state and unwrapped continuously, so
  that points of successive turns, which share a polar angle, keep their turn), and the
  obstacle is the staircase

      r_obs(psi) = r_hub + h sum_{k>=1} ramp((psi - 2 pi k) / w + 1),

  which climbs by h over the last w radians of every turn, where the turn passes over the root
  end. ramp is the C1 smoothstep on [0, 1]; w is about two elements. The turns rest on a
  prescribed surface: an outer turn's load does not reach the inner ones, and the turns' radii
  are imposed, not predicted.
- ``"surface"``: the obstacle is the hub alone, r_obs = r_hub, with a fairing behind the root
  clamp (:meth:`CoilContact.fairing_height`); the turns are kept apart by the contact of the
  tape's real surfaces with each other (:mod:`tapecoil.contact.self_contact`).

The winding angle is kept in both: the predictor, the measures and the pictures use it.

The bracket <g> is smoothed over a width delta (delta softplus(g/delta), ``contact.smoothing``
= delta/h, default 1/20): with the plain bracket Newton cycles as nodes enter and leave
contact. On the coarse benchmark h/20 takes fewer Newton iterations than the plain bracket
and than h/200, with the same energies and largest penetration (docs/notes/coiling.md). The price
of h/20: the tape rests a few delta off the coil and, near the lift-off point, that extra
support lowers the coiling tension (the axial-force balance of the coiling module) a little.
So the coiling-tension study uses the plain bracket.

The default stiffness k = E h / (100 l^2) (l the element length along the tape) makes the
contact stiffness of an element, k l^2, one hundredth of the membrane stiffness E h of the
element it pushes on. On the benchmark's coarse mesh with the spiral: with k l^2 = E h,
Newton chattered between contact sets and the run stalled early; with E h / 100 it coils the
whole 36 rad, the turns sinking into each other by a fraction of h (the most at the climbs
over the root step); with E h / 10^4 the turns sank by several h.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import dolfinx
import numpy as np
import ufl

from tapecoil.core import jit
from tapecoil.core.smoothing import penetration_slope_ufl, penetration_ufl, smoothstep, smoothstep_ufl
from tapecoil.hub.frame import HubFrame
from tapecoil.models.shell import NaghdiShell, Nodes

if TYPE_CHECKING:
    from tapecoil.config import Config

# what keeps the turns apart: the ideal spiral as an obstacle, or the turns' real surfaces
TURN_MODELS = ("spiral", "surface")


def spiral_obstacle(psi, r_hub: float, h: float, max_turns: int, ramp_width: float, step=smoothstep_ufl):
    """The ideal spiral's radius at winding angle ``psi`` (the module's staircase): ``r_hub`` [m],
    climbing by ``h`` [m] over the last ``ramp_width`` [rad] of each of ``max_turns`` turns.
    ``step``: :func:`smoothstep_ufl` for a UFL ``psi``, :func:`smoothstep` for numbers."""
    return r_hub + h * sum(step((psi - 2 * math.pi * k) / ramp_width + 1.0) for k in range(1, max_turns + 1))


def root_fairing(psi, r_hub: float, h: float, ramp_width: float):
    """The hub's radius with its fairing behind the root clamp, at winding angle ``psi`` (UFL):
    r_hub, rising smoothly to r_hub + h over the last ``ramp_width`` [rad] of the first turn,
    where the turn passes over the root's end (:meth:`CoilContact.fairing_height`, read by
    winding angle: behind the root's end by 2 pi - psi); r_hub again beyond, where the turn
    lies on the root and its own turns carry it."""
    behind = 2 * math.pi - psi
    on = ufl.And(ufl.gt(behind, 1e-6 * ramp_width), ufl.lt(behind, ramp_width))
    return r_hub + h * ufl.conditional(on, 1.0, 0.0) * smoothstep_ufl(1.0 - behind / ramp_width)


def default_penalty(E: float, h: float, element_length: float) -> float:
    """Penalty stiffness per unit area [N/m^3]: element contact stiffness E h / 100."""
    return 0.01 * E * h / element_length**2


@dataclass
class ContactSettings:
    """The hub's and the turns' contact, the full shell's and the hybrid's alike."""

    penalty: float  # [N/m^3] per unit area of the shell
    max_turns: int
    ramp_width: float  # [rad]
    smoothing: float  # [m]
    turns: str = "surface"  # what keeps the turns apart (contact.turns)
    buffer: float = 0.0  # [m] the search's Verlet buffer between the turns' surfaces

    @classmethod
    def from_config(cls, config: Config, element_length: float) -> ContactSettings:
        """The settings of ``config``'s [contact] for its tape on its hub, meshed with elements
        ``element_length`` [m] long along the tape."""
        tp, cc = config.tape, config.contact
        penalty = cc.penalty or cc.penalty_scale * default_penalty(
            config.wall.axial_modulus, tp.h, element_length
        )
        return cls(
            penalty,
            # the spiral's turns: enough for the winding the hub angle gives, with a margin
            math.ceil((config.coiling.hub_angle + math.pi) / (2 * math.pi)) + 1,
            # the climb over the root end spread over about two elements (at least 0.3 rad)
            max(2 * element_length / config.hub.radius, 0.3),
            cc.smoothing * tp.h,
            cc.turns,
            cc.search_margin * tp.h,
        )


class CoilContact:
    """Contact of the tape's inner face with the hub (penalty), and the winding angles.

    ``frame`` places the hub and gives its radius; ``max_turns`` bounds the number of turns of
    the ideal spiral; ``ramp_width`` [rad] is its climb w (see the module docstring);
    ``fairing``: in the surface mode, the fairing behind a root clamped on the hub (False: a
    bare cylinder, for a tape that is not clamped to it).
    """

    def __init__(
        self,
        model: NaghdiShell,
        frame: HubFrame,
        penalty: float,
        max_turns: int,
        ramp_width: float,
        smoothing: float = 0.0,
        turns: str = "spiral",
        fairing: bool = True,
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
        # the face's point relative to the axis (UFL): what the hub touches
        self.face = face = self._face(model.phi, model.d)
        self.radius = ufl.sqrt(face[0] ** 2 + face[2] ** 2)
        if turns not in TURN_MODELS:
            raise ValueError(f"contact between turns must be one of {TURN_MODELS}, got {turns!r}")
        self.turns = turns
        self.fairing = fairing and turns == "surface"
        self.hub_turn = dolfinx.fem.Constant(model.mesh, 0.0)
        if turns == "spiral":
            self.obstacle = spiral_obstacle(self.psi, r_hub, h, max_turns, ramp_width)
            # the hub carries the first turn up to the start of its climb; beyond, turns carry turns
            on_hub = ufl.conditional(ufl.lt(self.psi, 2 * math.pi - ramp_width), 1.0, 0.0)
        elif not fairing:  # a bare cylinder: no root is clamped on it
            self.obstacle = r_hub
            on_hub = 1.0
        else:
            # the hub's fairing behind the root clamp (see fairing_height), turned with the hub
            swept = frame.sign * ufl.atan2(face[2], face[0]) - 0.5 * math.pi - self.hub_turn
            behind = ufl.atan2(ufl.sin(swept), ufl.cos(swept))  # wrapped to (-pi, pi]
            on = ufl.And(ufl.gt(behind, 1e-6 * ramp_width), ufl.lt(behind, ramp_width))
            self.obstacle = r_hub + h * ufl.conditional(on, 1.0, 0.0) * smoothstep_ufl(
                1.0 - behind / ramp_width
            )
            on_hub = 1.0
        gap = self.obstacle - self.radius
        self.penetration = self._bracket(gap)
        # the push of the hub on the face per unit reference area [N/m^2]: the energy's slope in g
        self.pressure = self.stiffness * self.penetration * penetration_slope_ufl(gap, smoothing)
        density = 0.5 * self.stiffness * self.penetration**2 * model.jacobian
        self.energy = density * model.dx
        # what the hub itself pushes (the spiral's turns carry the rest): what its friction bounds
        self.hub_pressure = on_hub * self.pressure
        self.energy_hub = on_hub * density * model.dx
        self.energy_coil = (1.0 - on_hub) * density * model.dx if turns == "spiral" else None
        self.hub_angle = 0.0

    def _face(self, phi, d):
        """The inner face's point relative to the hub axis, for a mid-surface point and director."""
        return phi + self.face_offset * d - ufl.as_vector(self.axis_point)

    def _bracket(self, gap):
        """The penetration <gap>: max(gap, 0), or its smooth version delta softplus(gap / delta)."""
        return penetration_ufl(gap, self.smoothing)

    def energy_secant_form(self, q_old, director_variation):
        """Contact virtual work in the direction dq, energy-consistent from q_old to q.

        The penalty energy P(g) = k/2 <g>^2 of a quadrature point depends on the state through
        the gap g = r_obs - rho only (r_obs the obstacle's radius, rho = |face|_xz the face
        point's distance from the axis). Its force is written as the secant slope
        (P(g1) - P(g0)) / (g1 - g0) (the tangent at the mean gap when the gap hardly changes)
        times a variation of g that is exact along the step:
        rho1 - rho0 = (f0 + f1) . (f1 - f0) / (rho0 + rho1) in the xz-plane, with the director
        varied by ``director_variation`` (:meth:`NaghdiShell.director_variation`). Then the work
        along the step is the change of the contact energy (the winding angles and the hub, which
        place the obstacle, are held through a step).
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

    def spiral_radius(self, psi: np.ndarray) -> np.ndarray:
        """The radius [m] of the outer face of the turn beneath a point of winding angle psi on
        the ideal spiral (r_hub on the first turn, + h per turn, climbing over the root end)."""
        return spiral_obstacle(psi, self.r_hub, self.h, self.max_turns, self.ramp_width, smoothstep)

    def polar(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance from the axis and swept angle (:meth:`HubFrame.polar`) of points (3, n)."""
        return self.frame.polar(points)

    @property
    def turns_with_hub(self) -> bool:
        """Whether the obstacle's energy depends on the hub angle at a fixed tape: the surface
        mode's fairing behind the root turns with the hub; the spiral obstacle is read from the
        winding angles, which are the material's."""
        return self.turns == "surface"

    def turn(self, hub_angle: float) -> None:
        """Place the hub (its fairing) at the hub angle ``hub_angle`` [rad] (while it turns)."""
        self.hub_turn.value = hub_angle

    def fairing_height(self, swept: np.ndarray) -> np.ndarray:
        """Height [m] of the hub's surface above r_hub at swept angles ``swept`` (numpy).

        Behind the root's end (the angles the root has left, 0 < swept - hub angle < w) the hub
        carries a fairing that rises smoothly to the root's thickness h at the root's end, as a
        hub's clamp does: the end of the first turn climbs it onto the root instead of onto a
        step of height h, which a mesh coarser than h cannot follow.
        """
        if not self.fairing:
            return np.zeros_like(swept)
        behind = np.angle(np.exp(1j * (swept - float(self.hub_turn.value))))
        on = (behind > 1e-6 * self.ramp_width) & (behind < self.ramp_width)
        return np.where(on, self.h * smoothstep(1.0 - behind / self.ramp_width), 0.0)

    def nodal_penetration(self) -> np.ndarray:
        """Penetration [m] of the inner face into the obstacle (the hub and its fairing, or the
        spiral's turn beneath) at this rank's nodes (negative: a gap)."""
        q = self.model.q.x.array
        face = self.nodes.positions(q) + self.face_offset * self.nodes.directors(q)
        radius, swept = self.polar(face)
        if self.turns == "spiral":
            return self.spiral_radius(self.psi.x.array) - radius
        return self.r_hub + self.fairing_height(swept) - radius

    def radial_reaction(self) -> float:
        """The hub's push on the tape [N]: the radial components, away from the axis, of the
        force its contact (with the fairing) exerts on the tape's nodes, summed (collective)."""
        if getattr(self, "_reaction", None) is None:
            form = jit.form(ufl.derivative(self.energy_hub, self.model.q, self.model.dq))
            self._reaction = (form, dolfinx.fem.Function(self.model.W))
        form, force = self._reaction
        force.x.array[:] = 0.0
        dolfinx.fem.assemble_vector(force.x.array, form)
        force.x.scatter_reverse(dolfinx.la.InsertMode.add)
        n_owned = self.nodes.space.dofmap.index_map.size_local
        f = force.x.array[self.nodes.u_dofs[:n_owned]]  # dE/du at the owned nodes
        x = self.nodes.positions(self.model.q.x.array)[:, :n_owned].T - np.asarray(self.axis_point)
        radial = x.copy()
        radial[:, 1] = 0.0  # the axis is along y
        radial /= np.linalg.norm(radial, axis=1)[:, None]
        local = float(-np.einsum("ni,ni->", f, radial))
        return self.model.mesh.comm.allreduce(local)

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
