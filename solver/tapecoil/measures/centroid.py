"""Where a tape's section is: the centroid of the line of shell nodes across it, read from the
state alone (a shell's counterpart of a beam node's position)."""

from __future__ import annotations

import numpy as np

from tapecoil.models.nodes import Nodes

__all__ = ["section_centroid"]


def section_centroid(model, station: float, comm) -> np.ndarray:
    """The centroid [m] (3,) of the shell ``model``'s section at the line of nodes across it
    nearest ``station`` [m] along the tape (xi_1): the positions of its nodes averaged with
    Simpson's weights over the width, exact for the Q2 section's mid-surface with nodes
    equally spaced along its arc (collective; every rank)."""
    nodes = Nodes(model)
    owned = nodes.space.dofmap.index_map.size_local
    xi = nodes.xi[:, :owned]
    points = nodes.positions(model.q.x.array)[:, :owned]
    local = np.unique(xi[0])
    lines = np.concatenate(comm.allgather(local))
    if not len(lines):
        raise ValueError("section_centroid: the shell has no nodes")
    line = lines[np.argmin(np.abs(lines - station))]
    on = np.abs(xi[0] - line) <= 1e-9  # [m]: one line of nodes, millimetres from the next
    across = np.concatenate(comm.allgather(xi[1, on]))
    where = np.vstack(comm.allgather(points[:, on].T))
    order = np.argsort(across)
    across, where = across[order], where[order]
    if len(across) % 2 == 0 or not np.allclose(np.diff(across), across[1] - across[0], rtol=1e-9):
        raise ValueError("section_centroid: the nodes across are not the Q2 line of an even element count")
    weights = np.ones(len(across))
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    return weights @ where / weights.sum()
