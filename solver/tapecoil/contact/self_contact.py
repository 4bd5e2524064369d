"""Penalty contact of a surface with itself, from the current geometry of both sides.

Two parts of a shell of thickness h touch when their mid-surfaces come within h of each other
(the faces h/2 off the mid-surfaces meet). Every node A of the mid-surface is a contact point;
its partners are the closest points y of the other parts of the surface (the cells beyond
``exclusion`` from A in the reference configuration, so that A's own neighbourhood never
counts), found on the deformed surface: at most one on each side of A (the side of the
partner A was on at the last converged state), so that a turn of a coil is kept off the turn
beneath and off the turn above, and any part of the surface off any other. The gap is

    g = side (x_A - y) . n_s(y) - h,

n_s the partner's smoothed normal (its shape functions times the nodes' mean normals: the Q2
surface is only C0, and a node over an edge between two cells must be pushed the same way by
either), counted on the node's side so that a node pushed through its partner has g < -h and is
pushed back. A node whose closest point lies on an edge of the partner counts as over it up to
h beside that edge: beyond a free edge the face is extended by h (turns of one width lie edge
over edge), beside an inner edge the node lies over the next cell. The penalty energy is
w_A k/2 <-g>^2 (w_A the node's share of the reference area, k the stiffness per unit area, <.>
the bracket smoothed over a width delta as in the hub contact: delta softplus(-g / delta)). Its
force, dE/dg along B = side n_s (x) (1, -N_1, ..., -N_9), acts on A and, through the shape
functions N_b(y), on the nodes of the partner cell: equal and opposite, since sum_b N_b = 1.
Both faces' nodes are contact points (two-pass), so the pressure between two layers is the sum
of both passes. A node keeps its partner cell on a side while its closest point stays inside
it: of two nearly equally close cells (a node over the edge between them) the closer by
round-off would change from one Newton iteration to the next, and Newton would cycle.

Newton's operator is the force's exact derivative (:mod:`tapecoil.contact.linearisation`): on
each pair's 30 dofs (the closest point sliding along the partner, the turning of n_s and of the
shape functions with it), assembled with the shell's matrix; and through the nodal normals, on
the nodes of the cells around the partner cell, applied in the Krylov solve that the factorised
assembled matrix preconditions (:meth:`~tapecoil.contact.term.SelfContactTerm.apply_coupling`).
The force along the smoothed normal is not the gradient of an energy: the operator is not
symmetric.

The surface is a shell's mid-surface, or any :class:`~tapecoil.contact.surface.ContactSurface`
(a hybrid's shell window joined to the strip its beam sweeps); the pairs are computed on its
nodes' positions, and the term (:mod:`tapecoil.contact.term`) maps their forces and matrices to
the unknowns those nodes follow.

Parallel: the surface is small (nodes and cells of a 2D mesh), so every rank gathers all node
positions at each evaluation and searches for its own nodes' partners; the forces and the
matrix entries go to whichever ranks own the dofs (PETSc's stash). The search is a Verlet list
(:class:`~tapecoil.contact.projection.CandidateSearch`): rebuilt only when a node has moved by
more than half the buffer, and exact in between.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from tapecoil.contact import kernels
from tapecoil.contact.linearisation import NodalNormals
from tapecoil.contact.projection import CandidateSearch


def smoothed_bracket(gap: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The penetration p = <-gap> (smoothed over ``delta`` if > 0) and dp/dgap, d2p/dgap2."""
    if delta > 0.0:
        x = -gap / delta
        p = delta * (np.maximum(x, 0.0) + np.log1p(np.exp(-np.abs(x))))
        s = 0.5 * (1.0 + np.tanh(0.5 * x))  # the logistic function, stable for either sign
        return p, -s, s * (1.0 - s) / delta
    active = gap < 0.0
    return np.where(active, -gap, 0.0), -active.astype(float), np.zeros_like(gap)


@dataclass
class ContactPairs:
    """The contact pairs of one rank at one state: contact node, partner cell and the penalty.

    ``node`` (P,), ``cell`` (P,): the contact node and its partner cell; ``ref`` (P, 2),
    ``held`` (P, 2), ``N`` (P, 9): the closest point's reference coordinates, which of them are
    held on an edge, and the shape functions there; ``side`` (P,) and ``gap`` (P,);
    ``direction`` (P, 3) the unit normal the gap is counted along; ``B`` (P, 30): the force's
    direction on the node's and the partner cell's nodes' positions (the force is ``force`` B,
    ``force`` (P,) = dE/dg, ``stiffness`` (P,) = d2E/dg2);
    ``positions`` (N, 3) and ``nodal`` (N, 3): the surface's nodes and their unit normals at
    this state, ``normal_data`` what the normals' derivatives need; ``energy``: this rank's
    penalty energy [J]. The force's derivative is computed when a Jacobian asks for it
    (:meth:`SelfContact.jacobian_blocks`).
    """

    node: np.ndarray
    cell: np.ndarray
    ref: np.ndarray
    held: np.ndarray
    N: np.ndarray
    side: np.ndarray
    gap: np.ndarray
    direction: np.ndarray
    B: np.ndarray
    force: np.ndarray
    stiffness: np.ndarray
    positions: np.ndarray
    nodal: np.ndarray
    normal_data: dict
    energy: float
    blocks: tuple | None = None


def inside_cell(ref: np.ndarray, tolerance: float = 1e-9) -> np.ndarray:
    """Whether reference points (n, 2) lie strictly inside their cells (off every edge)."""
    return np.all((ref > tolerance) & (ref < 1 - tolerance), axis=1)


def nearest_on_each_side(node, cell, side, distance, inside, memory=None) -> np.ndarray:
    """Indices of the pairs kept: for each node and side, the partner cell it kept (``memory``
    (2 N,), updated here; -1 none) while its closest point stays ``inside`` it, else the closest.
    """
    keys = node * 2 + (side > 0)
    kept = np.zeros(len(node), dtype=bool) if memory is None else (memory[keys] == cell) & inside
    order = np.lexsort((distance, ~kept, side, node))
    key = keys[order]
    first = order[np.concatenate([[True], key[1:] != key[:-1]])] if len(order) else order
    if memory is not None:
        memory[keys[first]] = cell[first]
    return first


class SelfContact:
    """Self-contact of a surface (see the module docstring).

    ``surface``: a :class:`~tapecoil.contact.surface.ContactSurface` (a shell's mid-surface:
    :class:`~tapecoil.contact.surface.ShellSurface`); ``thickness`` h [m]; ``penalty`` k
    [N/m^3]; ``smoothing`` delta [m]; ``buffer`` the search's Verlet buffer [m];
    ``exclusion`` [m]: parts of the surface closer than this to a node in the material
    coordinates are its own neighbourhood. ``side_hint(node, cell)``: optional, +1 or -1 per
    candidate pair, the side of the cell (along the surface's orientation) the node belongs on
    where the converged state cannot tell (see :meth:`_sides`).
    """

    def __init__(self, surface, thickness, penalty, smoothing, buffer, exclusion, side_hint=None):
        self.surface = surface
        self.comm = surface.comm
        self.h, self.penalty, self.delta = thickness, penalty, smoothing
        # pairs beyond this gap carry no force (the smoothed bracket is below 1e-5 delta there)
        self.cutoff = 12.0 * smoothing
        self.n_nodes, self.owned = surface.n_nodes, surface.owned
        self.material, self.weights, self.cells = surface.material, surface.weights, surface.cells
        self.buffer, self.exclusion, self.side_hint = buffer, exclusion, side_hint
        self.reach = thickness + self.cutoff
        self.normal_field = NodalNormals(self.cells, self.n_nodes)
        self.timings = {
            "gather": 0.0,
            "search": 0.0,
            "projection": 0.0,
            "normal_derivatives": 0.0,
            "assembly": 0.0,
            "coupling": 0.0,
        }
        self._reference_version = 0
        self.accept()

    def new_search(self) -> CandidateSearch:
        return CandidateSearch(self.cells, self.material, self.exclusion, self.reach, self.buffer)

    def positions(self, state: list[np.ndarray] | None = None) -> np.ndarray:
        """Positions (N, 3) of every node of the surface at ``state`` (the blocks' local arrays;
        default the current one), on every rank (collective)."""
        t0 = time.perf_counter()
        out = self.surface.positions(state)
        self.timings["gather"] += time.perf_counter() - t0
        return out

    def accept(self, state: list[np.ndarray] | None = None) -> None:
        """Take ``state`` (default the current one) as the converged one the sides are read from
        (collective)."""
        self.reference_positions = self.positions(state)
        self._reference_version += 1

    def _sides(self, node: np.ndarray, cell: np.ndarray, search: CandidateSearch) -> dict:
        """Side of each candidate partner, and the projections' warm start.

        With a ``side_hint`` (the order of the turns of a coil) the side is the hint's. Without,
        it is read at the last converged state where the node lies over the partner cell there
        (its closest point inside the cell), else at the search's positions. Both can be wrong:
        material that comes onto a coil along its tangent lies ahead of the cells it will rest
        on, below their tangent planes; and a node that has gone through its partner in a
        converged step would stay through.
        """
        stamp = (search.searches, self._reference_version)
        if search.data.get("stamp") != stamp:
            converged = kernels.closest_points(node, cell, self.reference_positions, self.cells)
            if self.side_hint is not None:
                above = self.side_hint(node, cell) > 0
            else:
                now = kernels.closest_points(node, cell, search.positions_at_search, self.cells)
                above = np.where(
                    inside_cell(converged["ref"]),
                    np.einsum("pi,pi->p", converged["direction"], converged["normal"]) >= 0.0,
                    np.einsum("pi,pi->p", now["direction"], now["normal"]) >= 0.0,
                )
            search.data = {"stamp": stamp, "side": np.where(above, 1.0, -1.0), "start": converged["ref"]}
        return search.data

    def pairs(
        self,
        search: CandidateSearch,
        memory: np.ndarray | None = None,
        state: list[np.ndarray] | None = None,
    ) -> ContactPairs:
        """This rank's contact pairs at ``state`` (the blocks' local arrays; default the current
        one; collective: gathers positions).

        ``memory`` (2 N,): the partner cell each node had on each side (-1: none), kept while
        the node's closest point stays inside it and updated here; without it the closest
        cell is taken. Where two cells are (nearly) equally close (a node over the edge
        between them), the closest by round-off changes from one Newton iteration to the next
        and the force with it, and Newton cycles; a kept partner does not.
        """
        x = self.positions(state)
        t0 = time.perf_counter()
        node, cell = search.candidates(x, self.owned)
        t1 = time.perf_counter()
        data = self._sides(node, cell, search)
        nodal, normal_data = self.normal_field.normals(x)
        # from the converged state's projections (fixed between searches), so that the residual
        # is a function of the state alone
        found = kernels.closest_points(
            node, cell, x, self.cells, start=data["start"], iterations=6, nodal=nodal
        )
        side = data["side"]
        # the gap is counted along the partner's smoothed normal (the Q2 surface is only C0:
        # across an edge between two cells the cells' own normals jump, and a node over that
        # edge would be pushed one way or the other by whichever cell is the closer by
        # round-off), on the side the node was on at the converged state, so that a node that
        # has gone through the partner has a gap below -h and is pushed back. A node whose
        # closest point lies on an edge of the partner is over it only as far as h beside that
        # edge: beyond a free edge the face is taken as extended by h (turns of the same width
        # lie edge over edge, and their edges must not pass each other); beside an inner edge
        # the node lies over the cell next to it, which is its partner if it is not the node's
        # own neighbourhood. Counted along the normal alone, a node beside a cell of its own
        # section (just beyond the exclusion, in the plane of a flattened section) would be
        # taken for a node that has sunk a whole thickness into it
        over = inside_cell(found["ref"]) | (found["beside"] <= self.h)
        gap = side * found["along"] - self.h
        keep = np.flatnonzero(over & (gap < self.cutoff))
        first = keep[
            nearest_on_each_side(
                node[keep],
                cell[keep],
                side[keep],
                found["distance"][keep],
                inside_cell(found["ref"][keep]),
                memory,
            )
        ]
        node, cell, gap, side = node[first], cell[first], gap[first], side[first]
        ref, held, N = found["ref"][first], found["held"][first], found["N"][first]
        t2 = time.perf_counter()
        self.timings["search"] += t1 - t0
        self.timings["projection"] += t2 - t1

        B = kernels.pair_blocks(node, cell, x, self.cells, nodal, ref, held, side)
        p, dp, d2p = smoothed_bracket(gap, self.delta)
        kw = self.penalty * self.weights[node]
        return ContactPairs(
            node=node,
            cell=cell,
            ref=ref,
            held=held,
            N=N,
            side=side,
            gap=gap,
            direction=side[:, None] * found["smooth"][first],
            B=B,
            force=kw * p * dp,
            stiffness=kw * (dp**2 + p * d2p),
            positions=x,
            nodal=nodal,
            normal_data=normal_data,
            energy=float(np.sum(0.5 * kw * p**2)),
        )

    def jacobian_blocks(self, pairs: ContactPairs) -> tuple[np.ndarray, np.ndarray]:
        """The pairs' force differentiated at fixed nodal normals, (P, 30, 30), and with respect
        to m = N_b n_b at each closest point, (P, 30, 3) (computed once per pairs)."""
        if pairs.blocks is None:
            t0 = time.perf_counter()
            _, matrix, sensitivity = kernels.pair_blocks(
                pairs.node,
                pairs.cell,
                pairs.positions,
                self.cells,
                pairs.nodal,
                pairs.ref,
                pairs.held,
                pairs.side,
                pairs.force,
                pairs.stiffness,
                matrices=True,
            )
            pairs.blocks = (matrix, sensitivity)
            self.timings["assembly"] += time.perf_counter() - t0
        return pairs.blocks

    def normal_derivatives(self, pairs: ContactPairs) -> np.ndarray:
        """dn_k/dX_j (slots, 3, 3) of the nodal normals at ``pairs``' state, over each node's
        neighbourhood (:class:`~tapecoil.contact.linearisation.NodalNormals`)."""
        t0 = time.perf_counter()
        out = self.normal_field.derivatives(pairs.normal_data)
        self.timings["normal_derivatives"] += time.perf_counter() - t0
        return out

    def energy(self, pairs: ContactPairs) -> float:
        """The penalty energy of the whole surface [J] from every rank's ``pairs`` (collective)."""
        return self.comm.allreduce(pairs.energy, op=MPI.SUM)

    def nodal_forces(self, pairs: ContactPairs) -> np.ndarray:
        """The contact force dE/dx (N, 3) on every node of the surface from this rank's ``pairs``
        (this rank's share: sum over the ranks for the whole; rank-local)."""
        out = np.zeros((self.n_nodes, 3))
        rows = np.concatenate([pairs.node[:, None], self.cells[pairs.cell]], axis=1)
        np.add.at(out, rows.ravel(), (pairs.force[:, None] * pairs.B).reshape(-1, 3))
        return out

    def max_penetration(self, pairs: ContactPairs) -> float:
        """The deepest penetration -g of any part of the surface into another [m], >= 0 (collective)."""
        local = float(-pairs.gap.min()) if pairs.gap.size else 0.0
        return max(self.comm.allreduce(local, op=MPI.MAX), 0.0)
