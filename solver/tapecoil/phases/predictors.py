"""Initial guesses for the coiling's load steps: the shift of steady coiling, or the secant.

Each step starts from a predictor: material already on the coil turns rigidly with the hub; the
rest (ploy region and free part) takes the state of the material that was a wound length
ds = r dtheta further back along the tape (the "shift": steady coiling looks the same in the lab
frame from step to step), or, on meshes too coarse to interpolate along the tape, the secant
extrapolation of the last two converged states.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from tapecoil.core.smoothing import smoothstep
from tapecoil.models.shell import Nodes

PREDICTORS = ("shift", "secant")


def choose_predictor(setting: str, element_length: float, r_hub: float) -> str:
    """The predictor of a run: the setting, or for "auto" the shift where the mesh resolves the coil.

    The shift interpolates the state along the tape, which needs elements short against the
    turn they are wound into: on the benchmark (each predictor with its own largest step) the
    default mesh, its elements a third of the hub radius, takes a fraction of the secant's
    Newton iterations with the shift, and the coarse mesh, its elements about the hub radius,
    more (docs/notes/coiling.md). "auto" takes the shift up to elements of half the hub radius.
    """
    if setting != "auto":
        return setting
    return "shift" if element_length <= 0.5 * r_hub else "secant"


class AlongTape:
    """Values of the nodal state at points moved along the tape (xi_1), on every rank.

    The Q2 nodes lie on lines of constant xi_2 running the length of the tape. Each rank gathers
    the owned nodes' values (five per node: the whole state is some ten thousand numbers) and
    interpolates every line with a cubic spline through its nodes, so no rank needs more than its
    own nodes and every rank gets the same value at a shared node. A shift by a whole element
    reproduces the nodal values exactly.
    """

    def __init__(self, nodes: Nodes, comm):
        self.nodes, self.comm = nodes, comm
        self.n_owned = nodes.space.dofmap.index_map.size_local
        xi = np.hstack(comm.allgather(nodes.xi[:, : self.n_owned]))
        # lines: clusters of equal xi_2 (up to round-off), far apart compared with round-off
        levels = np.sort(xi[1])
        gap = 1e-9 * float(np.ptp(levels))
        breaks = levels[np.nonzero(np.diff(levels) > gap)[0] + 1]
        line_global = np.searchsorted(breaks, xi[1] + gap, side="right")
        line_local = np.searchsorted(breaks, nodes.xi[1] + gap, side="right")
        self.lines = []
        for k in range(len(breaks) + 1):
            members = np.nonzero(line_global == k)[0]
            members = members[np.argsort(xi[0, members])]
            self.lines.append((members, xi[0, members], np.nonzero(line_local == k)[0]))

    def values_at(self, q: np.ndarray, shift: float) -> np.ndarray:
        """(n, 5) array: u and theta at each local node's xi_1 + ``shift``, from the W-dof array q."""
        nodes, n = self.nodes, self.n_owned
        owned = np.column_stack([q[nodes.u_dofs[:n]], q[nodes.theta_dofs[:n]]])
        values = np.vstack(self.comm.allgather(owned))
        out = np.empty((nodes.xi.shape[1], values.shape[1]))
        for members, xi1, local in self.lines:
            spline = CubicSpline(xi1, values[members], axis=0)
            out[local] = spline(nodes.xi[0, local] + shift)
        return out


def wound_length(contact, angle_from: float, angle_to: float) -> float:
    """The length [m] of tape the hub winds on from ``angle_from`` to ``angle_to`` [rad]: the
    mid-surface radius of the turn being wound (``contact``'s spiral) times the angle."""
    radius = float(contact.spiral_radius(np.array([angle_from]))[0]) + 0.5 * contact.h
    return radius * (angle_to - angle_from)


def turn_wound(
    q, current, nodes, psi, frame, angle_from: float, dtheta: float, keep_theta_0: bool = True
) -> None:
    """Turn the material already on the coil rigidly with the hub in the guess ``q`` (W-dof
    array) from the converged state ``current``: nodes wound more than a radian behind the
    tangent point (winding angle ``psi`` below ``angle_from`` - 1) by the hub's step ``dtheta``
    [rad], blended into the guess already in ``q`` over the radian before it. ``keep_theta_0``:
    the wound nodes keep their converged theta_0 (else the guess's, blended the same way)."""
    w = smoothstep(angle_from - psi)[:, None]
    x = nodes.positions(current)
    turned = frame.turn_points(x, dtheta) - nodes.reference
    q[nodes.u_dofs] = w * turned.T + (1 - w) * q[nodes.u_dofs]
    # a turn about the width axis changes theta_1 alone
    rotated = current[nodes.theta_dofs[:, 1]] + frame.director_angle_change(dtheta)
    q[nodes.theta_dofs[:, 1]] = w[:, 0] * rotated + (1 - w[:, 0]) * q[nodes.theta_dofs[:, 1]]
    if keep_theta_0:
        kept = current[nodes.theta_dofs[:, 0]]
        q[nodes.theta_dofs[:, 0]] = w[:, 0] * kept + (1 - w[:, 0]) * q[nodes.theta_dofs[:, 0]]


class CoilingPredictor:
    """The predictor ``kind`` ("shift" or "secant") of a coiling run on ``tape`` (a TapeOnHub).

    :meth:`remember` each converged state; the secant keeps the one before the last for its
    extrapolation (and a restart restores it).
    """

    def __init__(self, tape, kind: str, comm):
        if kind not in PREDICTORS:
            raise ValueError(f"predictor must be one of {PREDICTORS}, got {kind!r}")
        self.tape, self.kind = tape, kind
        self._along_tape = AlongTape(tape.contact.nodes, comm) if kind == "shift" else None
        self._converged: list[tuple[float, np.ndarray]] = []

    def predict(self, q: np.ndarray, angle_from: float, angle_to: float) -> None:
        """Overwrite the state ``q`` (W-dof array, converged at ``angle_from``) with the guess at
        ``angle_to``.

        Material already on the coil (winding angle more than a radian behind the tangent point)
        turns rigidly with the hub. Near the tangent point and beyond, coiling is steady in the
        lab frame: the ploy region stays where it is while the tape runs through it, the free
        part slides along the guide. So with ``predictor = "shift"`` every such point takes the
        state of the material ds = r dtheta further back along the tape (r the radius of the turn
        being wound), with u_x lowered by ds; the two are blended over the last radian before the
        tangent point, where both hold. With ``"secant"`` that part is instead extrapolated from
        the last two converged states, which gets the ploy region wrong by about r dtheta^2 / 2
        (measurements in docs/notes/coiling.md).
        """
        current = q.copy()
        dtheta = angle_to - angle_from
        c = self.tape.contact
        nodes = c.nodes
        if self.kind == "shift":
            ds = wound_length(c, angle_from, angle_to)
            shifted = self._along_tape.values_at(current, -ds)
            q[nodes.u_dofs] = shifted[:, :3] - np.array([ds, 0.0, 0.0])
            q[nodes.theta_dofs] = shifted[:, 3:]
        else:
            last = self._converged[-2] if len(self._converged) == 2 else None
            if last is not None and angle_from - last[0] > 0:
                q += (current - last[1]) * (dtheta / (angle_from - last[0]))
        turn_wound(
            q, current, nodes, c.psi.x.array, self.tape.frame, angle_from, dtheta, self.kind == "shift"
        )

    def remember(self, angle: float, state: np.ndarray) -> None:
        """A converged state at hub angle ``angle`` (kept for the secant)."""
        self._converged = [*self._converged[-1:], (angle, state.copy())]

    def previous_converged(self) -> tuple[float, np.ndarray] | None:
        """(hub angle, state) of the converged step before the current one, if the secant uses it."""
        if self.kind != "secant" or len(self._converged) < 2:
            return None
        return self._converged[-2]

    def set_previous_converged(self, angle: float, state: np.ndarray) -> None:
        """Restore the secant's memory of the step before the current one (a restart)."""
        self._converged = [(angle, state.copy())]
