"""The rates of a moving tape carried over a window move: :func:`carry_motion` sets a new
hybrid's state as :func:`~tapecoil.models.window.carry_over` does and gives its velocities and
accelerations as the carry-over's derivatives along the old motion's path."""

from __future__ import annotations

import numpy as np

from tapecoil.models.window import carry_over

__all__ = ["carry_motion"]


def _rotation_vectors(R: np.ndarray) -> np.ndarray:
    """The rotation vectors (n, 3) of rotation matrices R (n, 3, 3) (all of angle below pi)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_rotvec() if len(R) else np.zeros((0, 3))


def _exp(vectors: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(vectors).as_matrix() if len(vectors) else np.zeros((0, 3, 3))


def carry_motion(old, new, old_rates, probe: float):
    """:func:`carry_over` of a moving tape: sets ``new``'s state from ``old``'s and returns
    ``new``'s rates, velocities and accelerations, (shell v, shell a, beam v, beam a) as dof
    arrays of each part's space (collective).

    ``old_rates``: ``old``'s, in the same order; the shell's are those of its state (u, theta),
    the beam's its nodes' (u', w) and (u'', w'), w the spatial angular velocity, as
    :class:`~tapecoil.models.beam_dynamics.BeamDynamics` keeps them. The carry-over is a map from
    the old state to the new one; the new rates are its derivatives along the old motion's path
    over a short time t: the old state moved to q + t v + t^2/2 a (the beam's node frames turned
    by exp(t w + t^2/2 w')), carried over at t = +-``probe`` [s] and at 0, and the central
    differences taken (the velocity (q+ - q-)/2t, the acceleration (q+ + q- - 2 q0)/t^2; a new
    beam node's w from the rotation vectors of its frames' turns). Where the states pass node by
    node the rates do exactly; where a section is placed by a beam's frame or fitted to a shell's
    section the rates are the placement's, centripetal terms included, to second order in the
    probe.
    """
    shell, beam = old.shell.model, old.beam.model
    shell_v, shell_a, beam_v, beam_a = (np.asarray(r) for r in old_rates)
    q_shell, q_beam, frames = shell.q.x.array.copy(), beam.q.x.array.copy(), beam.node_frames.copy()
    u_dofs, theta_dofs = beam.node_u_dofs, beam.node_theta_dofs
    target_shell, target_beam = new.shell.model, new.beam.model
    t_u, t_theta = target_beam.node_u_dofs, target_beam.node_theta_dofs
    carried = []
    for t in (probe, -probe):
        shell.q.x.array[:] = q_shell + t * shell_v + 0.5 * t * t * shell_a
        beam.q.x.array[:] = q_beam
        beam.q.x.array[u_dofs] += t * beam_v[u_dofs] + 0.5 * t * t * beam_a[u_dofs]
        beam.node_frames = _exp(t * beam_v[theta_dofs] + 0.5 * t * t * beam_a[theta_dofs]) @ frames
        carry_over(old, new)
        carried.append(
            (target_shell.q.x.array.copy(), target_beam.q.x.array.copy(), target_beam.node_frames.copy())
        )
    shell.q.x.array[:], beam.q.x.array[:], beam.node_frames = q_shell, q_beam, frames
    carry_over(old, new)  # last: the ties keep the shapes of the state itself
    (s_plus, b_plus, f_plus), (s_minus, b_minus, f_minus) = carried
    s0, b0, f0 = target_shell.q.x.array, target_beam.q.x.array, target_beam.node_frames
    new_shell_v = (s_plus - s_minus) / (2 * probe)
    new_shell_a = (s_plus + s_minus - 2 * s0) / probe**2
    new_beam_v, new_beam_a = np.zeros_like(b0), np.zeros_like(b0)
    new_beam_v[t_u] = (b_plus[t_u] - b_minus[t_u]) / (2 * probe)
    new_beam_a[t_u] = (b_plus[t_u] + b_minus[t_u] - 2 * b0[t_u]) / probe**2
    f0_t = np.transpose(f0, (0, 2, 1))
    turn_plus, turn_minus = _rotation_vectors(f_plus @ f0_t), _rotation_vectors(f_minus @ f0_t)
    new_beam_v[t_theta] = (turn_plus - turn_minus) / (2 * probe)
    new_beam_a[t_theta] = (turn_plus + turn_minus) / probe**2
    return new_shell_v, new_shell_a, new_beam_v, new_beam_a
