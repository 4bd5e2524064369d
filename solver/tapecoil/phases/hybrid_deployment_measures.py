"""What the hybrid's deployment reads of its state after every step: the energies of shell and
beam, the tape's angular momentum about the hub's axis, the deployed fraction on the hybrid's
centre line, and how far the flattened beam behind the window has lifted off its turn.

The deployed fraction is the full shell's measure (:func:`~tapecoil.measures.deployment.coiled_length`)
read on the hybrid's centre line: the beam's line and the window's middle line, their inner face
half a thickness inside them, each point's turn beneath placed by its winding angle on the
spiral of turns.
"""

from __future__ import annotations

import math

import numpy as np
import ufl

from tapecoil.core import jit
from tapecoil.core.dofs import global_scalar, global_size
from tapecoil.measures.deployment import LIFT_OFF_GAP, coil_looseness, coiled_length
from tapecoil.phases.deployment_forms import director_rates
from tapecoil.phases.hybrid_line import centre_line, winding_along
from tapecoil.phases.release import split_state

__all__ = ["HybridDeploymentMeasures", "coiled_along"]


def coiled_along(
    hybrid, frame, hub_angle: float, tape, line=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Along ``hybrid``'s centre line: the places [m], the winding angles [rad], the inner face's
    gaps to the spiral of turns [m], and the coiled length [m] (collective, or not with ``line``,
    the centre line already read: :func:`~tapecoil.phases.hybrid_line.centre_line`). ``frame``:
    the hub's (:class:`~tapecoil.hub.frame.HubFrame`), at ``hub_angle`` [rad]; ``tape``: the
    :class:`~tapecoil.config.TapeConfig`."""
    x, points = centre_line(hybrid) if line is None else line
    psi = winding_along(frame, hub_angle, points)
    obstacle = hybrid.shell.contact.spiral_radius(psi)
    gap = frame.polar(points.T)[0] - 0.5 * tape.h - obstacle
    return x, psi, gap, coiled_length(x, gap, obstacle, LIFT_OFF_GAP * tape.h)


class HybridDeploymentMeasures:
    """The measures of a :class:`~tapecoil.phases.hybrid_motion.HybridMotion` of ``hybrid`` on the
    hub ``frame`` at ``hub_angle`` [rad], the tape ``tape``; ``reach`` [m]: the stretch behind the
    window's start that the next moves place into shell, where :meth:`lift_off` reads the
    flattened beam's gap to its turn. Built with each window: its forms are the window's."""

    def __init__(self, hybrid, motion, frame, hub_angle: float, tape, reach: float):
        self.hybrid, self.motion, self.frame = hybrid, motion, frame
        self.hub_angle, self.tape, self.reach = hub_angle, tape, reach
        self.comm = hybrid.shell.model.mesh.comm
        shell = hybrid.shell.model
        v_u, v_theta = split_state(motion.shell_scheme.v_old)
        _, d_dot, _ = director_rates(shell, shell.theta, v_theta)
        rho, h = tape.density, tape.h
        kinetic = 0.5 * rho * h * (ufl.dot(v_u, v_u) + h**2 / 12 * ufl.dot(d_dot, d_dot))
        self._shell_kinetic = jit.form(kinetic * shell.jacobian * shell.dx)
        self._strain = jit.form(shell.strain_energy)
        self._contact = jit.form(hybrid.shell.contact.energy)
        beam = hybrid.beam
        self._beam_contact = jit.form(sum(beam.energy_terms)) if beam.energy_terms else None
        spin = motion.shell_forms.angular_momentum(frame)
        self._shell_momentum = jit.form(spin * shell.jacobian * shell.dx)

    def window(self) -> tuple[float, float]:
        """The shell window's start and end along the tape [m]."""
        (start, end), _ = self.hybrid.shell.surface.xi_range
        return float(start), float(end)

    def dofs(self) -> int:
        """The hybrid's unknowns: its shell's and its beam's (collective)."""
        h = self.hybrid
        return global_size(h.shell.model.W) + global_size(h.beam.model.W)

    def strain_energy(self) -> float:
        """The strain energy of shell and beam [J] (collective)."""
        return global_scalar(self._strain, self.comm) + self.hybrid.beam.model.strain_energy()

    def contact_energy(self) -> float:
        """The penalty energy of the shell's and the beam's contact with the hub and the turns
        [J] (collective)."""
        beam = 0.0 if self._beam_contact is None else global_scalar(self._beam_contact, self.comm)
        return global_scalar(self._contact, self.comm) + beam

    def kinetic_energy(self) -> float:
        """The kinetic energy of shell and beam [J], from the last converged rates (collective)."""
        return global_scalar(self._shell_kinetic, self.comm) + self.motion.beam.kinetic_energy()

    def energies(self) -> dict[str, float]:
        """The strain, contact and kinetic energy [J] (collective)."""
        return {
            "strain": self.strain_energy(),
            "contact": self.contact_energy(),
            "kinetic": self.kinetic_energy(),
        }

    def angular_momentum(self) -> float:
        """The angular momentum of shell and beam about the hub's axis [kg m^2/s], from the last
        converged rates (collective): the tape's alone, which the root's torque changes (a free
        hub's own is its rotor's)."""
        frame = self.frame
        momentum, spin = np.split(self.motion.beam.momenta(), 2)  # the beam's, about the origin
        beam = np.dot(frame.axis, spin - np.cross(frame.axis_point, momentum))
        return global_scalar(self._shell_momentum, self.comm) + float(beam)

    def lift_off(self) -> dict[str, float]:
        """The coiled length [m] and the deployed fraction lambda, the coil's opening behind the
        lift-off and where [m] and the loose turns beyond it
        (:func:`~tapecoil.measures.deployment.coil_looseness`), and the
        flattened beam's largest gap to its turn [m] within ``reach`` behind the window's start,
        and where [m] (collective)."""
        tp = self.tape
        x, points = centre_line(self.hybrid)
        x, psi, gap, coiled = coiled_along(self.hybrid, self.frame, self.hub_angle, tp, (x, points))
        radius, angle = self.frame.polar(points.T)
        # the stretch of beam that the next moves place into shell, where it rests on a turn
        # (on the hub, by the root, the release lifts it by a few thicknesses: docs/notes/hybrid.md)
        start = self.window()[0]
        behind = (x < start - 1e-9 * tp.L) & (x > start - self.reach) & (psi > 2 * math.pi)
        loosest = int(np.argmax(np.where(behind, gap, -np.inf))) if behind.any() else None
        return {
            "coiled_length": coiled,
            "lambda": 1.0 - coiled / tp.L,
            **coil_looseness(x, radius, angle, coiled, tp.h),
            "beam_gap": float(gap[loosest]) if loosest is not None else 0.0,
            "beam_gap_at": float(x[loosest]) if loosest is not None else 0.0,
        }
