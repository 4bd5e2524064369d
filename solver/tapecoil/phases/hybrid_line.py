"""The hybrid's centre line: the beam's nodes and the shell window's nodes on its middle line,
in order along the tape, and their winding angles about the hub (collective where it gathers).
"""

from __future__ import annotations

import math

import numpy as np

from tapecoil.hub.frame import HubFrame
from tapecoil.models.nodes import Nodes

__all__ = ["centre_line", "winding_along"]


def _gathered(comm, *arrays) -> list[np.ndarray]:
    return [np.concatenate(comm.allgather(np.ascontiguousarray(a))) for a in arrays]


def centre_line(hybrid) -> tuple[np.ndarray, np.ndarray]:
    """The tape's line along its length: reference coordinates x [m] (sorted) and current points
    (n, 3) [m], from the beam's nodes and the shell's nodes on its middle line, gathered on every
    rank (collective)."""
    comm = hybrid.shell.strip.mesh.comm
    beam = hybrid.beam.model
    nodes = Nodes(hybrid.shell.model)
    middle = np.abs(nodes.xi[1]) < 1e-9 * hybrid.shell.surface.xi_range[1][1]
    x_shell = nodes.xi[0, middle]
    p_shell = nodes.positions(hybrid.shell.model.q.x.array)[:, middle].T
    x_beam = beam.node_points[:, 0]
    p_beam = beam.node_points + beam.q.x.array[beam.node_u_dofs]
    x, points = _gathered(comm, np.concatenate([x_shell, x_beam]), np.vstack([p_shell, p_beam]))
    order = np.argsort(x, kind="stable")
    x, points = x[order], points[order]
    keep = np.concatenate([[True], np.diff(x) > 1e-12])  # a node shared by ranks, once
    return x[keep], points[keep]


def winding_along(frame: HubFrame, angle: float, points: np.ndarray) -> np.ndarray:
    """The winding angles [rad] of points (n, 3) along the tape from its root at hub angle
    ``angle``: the hub angle less each point's swept angle, unwrapped along the tape from the
    root's, 0 (successive points less than half a turn apart)."""
    raw = angle - frame.polar(points.T)[1]
    psi = np.unwrap(raw)
    return psi - 2 * math.pi * np.round(psi[0] / (2 * math.pi))
