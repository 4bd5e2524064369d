"""Coulomb friction between the tape's face and the rigid hub, by a return mapping.

Each quadrature point of the face pressed on the hub (the penalty contact of
:class:`~tapecoil.hub.contact.CoilContact`, pressure p = k <g> <g>' per unit reference area) is tied
to an *anchor* on the hub's surface, a point fixed in the hub's turning frame: its angle about
the axis and its place along it. The slip s from the anchor, measured on the hub's surface
(r_hub times the angle, and along the axis), is resisted by the traction

    tau = eps s              while eps |s| <= mu p   (stick: an elastic spring of stiffness eps)
    tau = mu p s / |s|       otherwise               (slip: the Coulomb bound, along the slip)

and once a step is accepted the anchor is moved so that what remains of s is tau / eps: the
slip beyond the spring's reach is permanent and dissipates tau . (the anchor's move). This is
the return mapping of elastoplasticity applied to the tangential gap (Wriggers, *Computational
Contact Mechanics*, 2nd ed. 2006, Sec. 5.2 and 10.4; Laursen 2002): exact Coulomb sliding at
|tau| = mu p, and sticking up to a creep of mu p / eps, which with the tangential stiffness
equal to the normal penalty is mu times the normal penetration, a small part of h. The
traction's work is written with the variation of s (the point's angle and axial place), so the
Jacobian (UFL's derivative of the residual, return map and pressure included) is the
consistent one; it is unsymmetric as soon as a point slips, so solvers factorise it by LU.

Not an energy: the residual term is :attr:`HubFriction.residual`. What the tangential spring
holds, :meth:`HubFriction.spring_energy`, is recoverable; what slip has dissipated is
:attr:`HubFriction.dissipated`, summed step by step from the anchors' moves.
"""

from __future__ import annotations

import dolfinx
import numpy as np
import ufl

from tapecoil.core import compat, jit
from tapecoil.core.dofs import global_scalar
from tapecoil.core.expression import expression_at


class HubFriction:
    """Coulomb friction ``mu`` [-] on the hub of ``contact`` (a
    :class:`~tapecoil.hub.contact.CoilContact`), with tangential stiffness ``stiffness`` per unit
    reference area [N/m^3] (default: the contact's normal penalty).

    The anchors start where the face points are (:meth:`reset`, a state without friction
    forces); :meth:`commit` after every accepted step moves them and adds the step's dissipation.
    ``anchor`` (angle in the hub's frame [rad], axial place [m], at the quadrature points) is
    the state a checkpoint keeps with the tape's.
    """

    def __init__(self, contact, mu: float, stiffness: float | None = None):
        if not mu > 0:
            raise ValueError(f"a friction coefficient must be positive, got {mu!r}")
        import basix.ufl

        model = contact.model
        self.model, self.contact, self.mu = model, contact, float(mu)
        mesh = model.mesh
        k = float(contact.stiffness.value) if stiffness is None else float(stiffness)
        if not k > 0:
            raise ValueError(f"the tangential stiffness must be positive, got {k!r}")
        self.stiffness = dolfinx.fem.Constant(mesh, k)
        element = basix.ufl.quadrature_element(mesh.basix_cell(), value_shape=(2,), degree=model.q_full)
        self.space = dolfinx.fem.functionspace(mesh, element)
        self.anchor = dolfinx.fem.Function(self.space, name="friction_anchor")
        self._traction_q = dolfinx.fem.Function(self.space)  # tau at the last commit
        self._move = dolfinx.fem.Function(self.space)  # the anchors' last move, on the hub's surface
        r_hub = contact.r_hub
        self.r_hub = r_hub

        face = contact.face
        # the face point's angle in the hub's turning frame, increasing in the sense the hub turns
        self.angle = contact.frame.sign * ufl.atan2(face[2], face[0]) - contact.hub_turn
        turned = self.angle - self.anchor[0]
        self.slip = ufl.as_vector(
            [r_hub * ufl.atan2(ufl.sin(turned), ufl.cos(turned)), face[1] - self.anchor[1]]
        )
        self.pressure = contact.hub_pressure  # per unit reference area
        eps, bound = self.stiffness, self.mu * self.pressure
        trial = eps * self.slip
        # |s| kept off zero only where the slip branch is not taken (s = 0 sticks)
        length = ufl.sqrt(ufl.dot(self.slip, self.slip) + (1e-12 * contact.h) ** 2)
        self.traction = ufl.conditional(
            ufl.le(ufl.dot(trial, trial), bound**2), trial, bound * self.slip / length
        )
        self.residual = (
            ufl.dot(self.traction, ufl.derivative(self.slip, model.q, model.dq)) * model.jacobian * model.dx
        )
        points = compat.interpolation_points(self.space)
        self._position = expression_at(ufl.as_vector([self.angle, face[1]]), points)
        self._traction = expression_at(self.traction, points)
        self._new_anchor = expression_at(
            ufl.as_vector([self.angle - self.traction[0] / (eps * r_hub), face[1] - self.traction[1] / eps]),
            points,
        )
        self._spring = jit.form(0.5 * ufl.dot(self.traction, self.traction) / eps * model.jacobian * model.dx)
        self._dissipation = jit.form(ufl.dot(self._traction_q, self._move) * model.jacobian * model.dx)
        self.dissipated = 0.0  # [J] by slip since reset
        self._torque = None  # compiled on first use: a deployment never reads it

    def reset(self) -> None:
        """Anchors where the face points are now: no friction force, nothing dissipated."""
        self.anchor.interpolate(self._position)
        self.anchor.x.scatter_forward()
        self._traction_q.x.array[:] = 0.0
        self.dissipated = 0.0

    def commit(self) -> float:
        """After an accepted step: the anchors moved by the step's permanent slip, and its
        dissipation tau . (the anchors' move) added to :attr:`dissipated`. Returns the step's
        dissipation [J] (collective)."""
        old = self.anchor.x.array.copy()
        self._traction_q.interpolate(self._traction)
        self.anchor.interpolate(self._new_anchor)
        moved = (self.anchor.x.array - old).reshape(-1, 2)
        moved[:, 0] = self.r_hub * np.angle(np.exp(1j * moved[:, 0]))  # on the hub's surface [m]
        self._move.x.array[:] = moved.ravel()
        step = global_scalar(self._dissipation, self.model.mesh.comm)
        self.dissipated += step
        return step

    def hub_torque(self) -> float:
        """The torque the hub exerts on the tape through friction, in the sense the hub turns
        [N m] (collective): its work per radian of the hub turned under the tape, -tau_theta
        r_hub over the face (a turn of the hub moves every anchor by r_hub per radian)."""
        if self._torque is None:
            m = self.model
            self._torque = jit.form(-self.r_hub * self.traction[0] * m.jacobian * m.dx)
        return global_scalar(self._torque, self.model.mesh.comm)

    def spring_energy(self) -> float:
        """The energy the tangential springs of the sticking points hold [J] (collective)."""
        return global_scalar(self._spring, self.model.mesh.comm)
