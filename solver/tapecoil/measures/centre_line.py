"""The tape's centre line at the current state, and the coil's length and radius measured on it.

The functions take a :class:`~tapecoil.phases.tape_on_hub.TapeOnHub` first and are also its
methods (``tape.coil_geometry(angle)``). All are collective.
"""

from __future__ import annotations

import math

import numpy as np
from mpi4py import MPI

# ``tape`` below: a tape on its hub as the phases hold it (tapecoil.phases.tape_on_hub.TapeOnHub),
# read, never named: the measures sit below the phases


def centre_nodes(tape) -> np.ndarray:
    """Mask of this rank's owned nodes on the centre line (the line of xi_2 nearest 0; collective)."""
    nodes = tape.contact.nodes
    distance = np.abs(nodes.xi[1, : nodes.space.dofmap.index_map.size_local])
    local_min = distance.min() if distance.size else np.inf
    return distance <= tape.comm.allreduce(local_min, op=MPI.MIN) + 1e-9 * tape.config.tape.b


def _line(tape, mask: np.ndarray) -> dict[str, np.ndarray]:
    """The owned nodes of ``mask`` on every rank, sorted along the tape: xi_1, psi, radius."""
    nodes = tape.contact.nodes
    n_owned = nodes.space.dofmap.index_map.size_local
    radius, _ = tape.contact.polar(nodes.positions(tape.model.q.x.array)[:, :n_owned])
    local = np.column_stack(
        [nodes.xi[0, :n_owned][mask], tape.contact.psi.x.array[:n_owned][mask], radius[mask]]
    )
    rows = np.vstack(tape.comm.allgather(local))
    rows = rows[np.argsort(rows[:, 0])]
    return {"xi1": rows[:, 0], "psi": rows[:, 1], "radius": rows[:, 2]}


def edge_lines(tape) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The two free edges (xi_2 = -b/2 and +b/2) of the whole tape, as :func:`centre_line`
    (collective, every rank)."""
    nodes = tape.contact.nodes
    xi2 = nodes.xi[1, : nodes.space.dofmap.index_map.size_local]
    half = tape.config.tape.b / 2
    near = 1e-9 * tape.config.tape.b
    return _line(tape, xi2 <= -half + near), _line(tape, xi2 >= half - near)


def centre_line(tape) -> dict[str, np.ndarray]:
    """Centre-line nodes of the whole tape, sorted along it (collective, every rank).

    Columns: xi_1, winding angle psi, mid-surface distance from the hub axis.
    """
    return _line(tape, centre_nodes(tape))


def coil_geometry(tape, angle: float) -> dict[str, float]:
    """Coiled length and outer coil radius [m] (collective).

    The coiled length is the material length behind the tangent point, where the centre
    line's winding angle equals the hub angle. The outer radius is that of the outer face of
    the last turn half a turn behind the tangent point (mid-surface distance + h/2): at the
    tangent point itself the tape is already lifting off into the ploy region.
    """
    line = centre_line(tape)
    psi, xi1, radius = line["psi"], line["xi1"], line["radius"]
    h = tape.config.tape.h
    if angle <= psi[0]:
        return {"coiled_length": 0.0, "outer_radius": float(radius[0] + h / 2)}
    s = float(np.interp(angle, psi, xi1))
    probe = angle - math.pi if angle > math.pi else angle
    r = float(np.interp(probe, psi, radius))
    return {"coiled_length": s, "outer_radius": r + 0.5 * h}
