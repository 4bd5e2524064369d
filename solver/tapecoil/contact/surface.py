"""The surfaces a self-contact is computed on: nodes, Q2 cells, and how the nodes follow the unknowns.

A contact surface is a set of nodes and biquadratic (9-node) cells, held whole on every rank
(the surface of a 2D mesh is small): their reference data gathered once, their positions at
each state by one gather. It is made of parts, each the surface of one block of unknowns (one
problem's state; a coupled solver joins several):

- :class:`ShellSurface`: a shell's mid-surface, its Q2 nodes and cells; a node's position is its
  reference position plus its displacement.
- :class:`BeamStripSurface`: the strip a beam's flat section sweeps. At each node of the beam's
  chosen elements, three points across the section (its two edges and its middle, at
  ``offsets`` in the section's frame) are carried by the node's section frame; the P2 elements
  become Q2 cells, three points along by three across (the middle row on the beam's line). A
  point's position is the node's line position plus the node's rotation of its offset,
  x = X + u + R(theta) Lambda_n p, so it follows the node's displacement and rotation dofs.
- :class:`JoinedSurface`: parts one after the other (a hybrid's shell window on its beam's coil).

A node's position depends on its block's unknowns through :meth:`ContactSurface.unknowns`: its
displacement dofs (x moves with them one to one) and, on a beam strip, its rotation dofs with
dx/dtheta (3 x 3) and the second derivative, contracted with a force, that Newton's matrix takes
(:mod:`tapecoil.core.rotation`). Dofs are global, in each block's own numbering.
"""

from __future__ import annotations

from dataclasses import dataclass

import dolfinx
import numpy as np
import ufl

from tapecoil.core import compat, jit
from tapecoil.core.rotation import rotated, rotated_derivative, rotated_second_derivative

__all__ = ["BeamStripSurface", "ContactSurface", "JoinedSurface", "ShellSurface", "Unknowns"]


@dataclass
class Unknowns:
    """How the nodes of a surface follow the unknowns at a state.

    ``block`` (N,): the block each node's unknowns belong to; ``u`` (N, 3): its displacement
    dofs (global, in the block's numbering); ``theta`` (N, 3): its rotation dofs, -1 for a node
    that no rotation carries; ``jacobian`` (N, 3, 3): dx/dtheta (zero where no rotation).
    """

    block: np.ndarray
    u: np.ndarray
    theta: np.ndarray
    jacobian: np.ndarray


def _owned_global(index_map, local: np.ndarray) -> np.ndarray:
    return index_map.local_to_global(np.asarray(local, dtype=np.int32)).astype(np.int64)


def _global_dofs(V, local_dofs: np.ndarray) -> np.ndarray:
    """Global indices of the local dofs ``local_dofs`` of the (blocked) space V."""
    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    local_dofs = np.asarray(local_dofs)
    return _owned_global(imap, local_dofs // bs) * bs + local_dofs % bs


class _Gather:
    """Per-node values of the nodes each rank owns, assembled on every rank in one order."""

    def __init__(self, comm, owned_global: np.ndarray, n_nodes: int):
        self.comm = comm
        self.n_nodes = n_nodes
        self._counts = np.array(comm.allgather(len(owned_global)), dtype=np.int64)
        self._order = np.concatenate(comm.allgather(np.asarray(owned_global, dtype=np.int64)))

    def __call__(self, values: np.ndarray) -> np.ndarray:
        """``values`` (n_owned, ...) of this rank's owned nodes, for every node (collective)."""
        values = np.ascontiguousarray(values)
        width = int(np.prod(values.shape[1:], dtype=np.int64))
        received = np.empty(self.n_nodes * width, dtype=values.dtype)
        self.comm.Allgatherv(values.ravel(), [received, width * self._counts])
        out = np.empty((self.n_nodes, *values.shape[1:]), dtype=values.dtype)
        out[self._order] = received.reshape(-1, *values.shape[1:])
        return out


class ContactSurface:
    """What a self-contact needs of a surface (see the module): ``n_nodes``; ``owned`` the nodes
    this rank takes as contact points; ``material`` (N, 2) their material coordinates (along
    the tape, across it); ``weights`` (N,) their shares of the reference area; ``cells`` (Nc, 9);
    ``comm``; ``blocks`` the number of blocks of unknowns; ``carried`` whether any node is
    carried by a rotation."""

    n_nodes: int
    owned: np.ndarray
    material: np.ndarray
    weights: np.ndarray
    cells: np.ndarray
    comm: object
    blocks: int = 1
    carried: bool = False

    def state(self) -> list[np.ndarray]:
        """The current state of every block (its Functions' local arrays)."""
        raise NotImplementedError

    def positions(self, state: list[np.ndarray] | None = None) -> np.ndarray:
        """The nodes' positions (N, 3) at ``state`` (default the current one; collective)."""
        raise NotImplementedError

    def unknowns(self, state: list[np.ndarray] | None = None) -> Unknowns:
        """How the nodes follow the unknowns at ``state`` (collective)."""
        raise NotImplementedError

    def values(self, owned: list[np.ndarray], state: list[np.ndarray] | None = None) -> np.ndarray:
        """The change of the nodes' positions (N, 3) for a change of the unknowns given by each
        block's owned values ``owned`` (linearised at ``state``; collective)."""
        raise NotImplementedError

    def rotation_hessian(self, forces: np.ndarray, state: list[np.ndarray] | None = None) -> np.ndarray:
        """sum_i f_i d2x_i/dtheta dtheta (N, 3, 3) for nodal forces ``forces`` (N, 3) (zero where
        no rotation carries the node; collective)."""
        raise NotImplementedError


class ShellSurface(ContactSurface):
    """A shell's mid-surface (:class:`~tapecoil.models.shell.NaghdiShell` and its
    :class:`~tapecoil.models.shell.Nodes`): every Q2 node, every cell; material coordinates the
    parameter domain's (xi1 along the tape, xi2 across)."""

    def __init__(self, model, nodes, block: int = 0):
        self.model, self.nodes, self.block = model, nodes, block
        self.comm = comm = model.mesh.comm
        imap = nodes.space.dofmap.index_map
        self.n_owned = n_owned = imap.size_local
        global_node = _owned_global(imap, np.arange(n_owned + imap.num_ghosts))
        self.n_nodes = imap.size_global
        self.owned = global_node[:n_owned]
        self._gather = _Gather(comm, self.owned, self.n_nodes)
        test = ufl.TestFunction(nodes.space)
        area = dolfinx.fem.assemble_vector(jit.form(test * model.jacobian * model.dx))
        area.scatter_reverse(dolfinx.la.InsertMode.add)
        self.reference = self._gather(nodes.reference[:, :n_owned].T.copy())
        self.material = self._gather(nodes.xi[:, :n_owned].T.copy())
        self.u_dofs = self._gather(_global_dofs(model.W, nodes.u_dofs[:n_owned].ravel()).reshape(-1, 3))
        self.weights = self._gather(area.array[:n_owned].copy())
        n_cells = model.mesh.topology.index_map(model.mesh.topology.dim).size_local
        self.cells = np.vstack(comm.allgather(global_node[nodes.space.dofmap.list[:n_cells]]))

    def state(self) -> list[np.ndarray]:
        return [self.model.q.x.array]

    def gather(self, values: np.ndarray) -> np.ndarray:
        """Per-node values of this rank's owned nodes, for every node (collective)."""
        return self._gather(values)

    def gather_u(self, q: np.ndarray) -> np.ndarray:
        """The u components (N, 3) of every node of the W-dof array ``q`` (its owned part at
        least), on every rank (collective)."""
        return self._gather(q[self.nodes.u_dofs[: self.n_owned]])

    def positions(self, state=None) -> np.ndarray:
        q = self.model.q.x.array if state is None else state[0]
        return self.gather_u(q) + self.reference

    def unknowns(self, state=None) -> Unknowns:
        n = self.n_nodes
        return Unknowns(
            np.full(n, self.block), self.u_dofs, np.full((n, 3), -1, dtype=np.int64), np.zeros((n, 3, 3))
        )

    def values(self, owned, state=None) -> np.ndarray:
        return self.gather_u(owned[self.block])

    def rotation_hessian(self, forces, state=None) -> np.ndarray:
        return np.zeros((self.n_nodes, 3, 3))


# the Q2 cell's nodes (basix order) as (point along the element, point across the section):
# along 0, 1, 2 the element's first vertex, its middle, its last vertex (P2 dofs 0, 2, 1)
_Q2_ALONG = np.array([0, 2, 0, 2, 1, 0, 2, 1, 1])
_Q2_ACROSS = np.array([0, 0, 2, 2, 0, 1, 1, 2, 1])
_P2_OF_ALONG = np.array([0, 2, 1])


class BeamStripSurface(ContactSurface):
    """The strip swept by the flat section of a :class:`~tapecoil.models.beam.GeometricallyExactBeam`
    over its elements ``cells`` (local indices of owned cells; see the module): three points
    across each node, at the section-frame offsets ``offsets`` (3, 3) (the edges and the middle,
    in that order across), carried by the node's frame. Material coordinates: the node's
    reference coordinate along the line (the first), the offset's along the section's axis 2."""

    carried = True

    def __init__(self, beam, cells: np.ndarray, offsets: np.ndarray, block: int = 1):
        self.beam, self.block = beam, block
        self.offsets = np.asarray(offsets, dtype=float).reshape(3, 3)
        mesh = beam.mesh
        self.comm = comm = mesh.comm
        space, _ = compat.collapse(beam.W.sub(0).sub(0))
        imap = space.dofmap.index_map
        n_owned = imap.size_local
        local_global = _owned_global(imap, np.arange(n_owned + imap.num_ghosts))
        self._n_owned = n_owned
        n_beam = imap.size_global
        self._gather = _Gather(comm, local_global[:n_owned], n_beam)
        dofmap = np.asarray(space.dofmap.list)
        chosen = np.vstack(comm.allgather(local_global[dofmap[np.asarray(cells, dtype=np.int32)]]))
        if len(chosen) == 0:
            raise ValueError("a beam strip surface needs at least one element")
        # the beam nodes of the chosen elements, numbered compactly
        self.beam_nodes = np.unique(chosen)
        compact = np.full(n_beam, -1, dtype=np.int64)
        compact[self.beam_nodes] = np.arange(len(self.beam_nodes))
        n = len(self.beam_nodes)
        self.n_nodes = 3 * n
        element = compact[chosen]  # (Nc, 3) in P2 order: first vertex, last vertex, middle
        self.cells = 3 * element[:, _P2_OF_ALONG[_Q2_ALONG]] + _Q2_ACROSS
        owned_beam = compact[local_global[:n_owned]]
        self.owned = (3 * owned_beam[owned_beam >= 0, None] + np.arange(3)).ravel()

        W = beam.W
        self._u_local = beam.node_u_dofs[:n_owned]
        self._theta_local = beam.node_theta_dofs[:n_owned]
        self.reference_line = self._gather(beam.node_points[:n_owned])[self.beam_nodes]
        u_global = self._gather(_global_dofs(W, self._u_local.ravel()).reshape(-1, 3))[self.beam_nodes]
        theta_global = self._gather(_global_dofs(W, self._theta_local.ravel()).reshape(-1, 3))[
            self.beam_nodes
        ]
        self.u_dofs = np.repeat(u_global, 3, axis=0)
        self.theta_dofs = np.repeat(theta_global, 3, axis=0)
        across = self.offsets[:, 1]
        self.material = np.column_stack([np.repeat(self.reference_line[:, 0], 3), np.tile(across, n)])
        # Simpson's weights along each element (its vertices l/6, its middle 4 l/6) and across
        lengths = np.linalg.norm(
            self.reference_line[element[:, 1]] - self.reference_line[element[:, 0]], axis=1
        )
        along = np.zeros(n)
        np.add.at(along, element[:, 0], lengths / 6)
        np.add.at(along, element[:, 1], lengths / 6)
        np.add.at(along, element[:, 2], 4 * lengths / 6)
        width = across[2] - across[0]
        self.weights = (along[:, None] * (width * np.array([1.0, 4.0, 1.0]) / 6)).ravel()

    def state(self) -> list[np.ndarray]:
        return [self.beam.q.x.array]

    def _nodes_at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Line positions (n, 3), rotation increments (n, 3) and committed frames (n, 3, 3) of
        the strip's beam nodes at the beam state ``q`` (collective)."""
        owned = np.concatenate(
            [q[self._u_local], q[self._theta_local], self.beam.node_frames[: self._n_owned].reshape(-1, 9)],
            axis=1,
        )
        every = self._gather(owned)[self.beam_nodes]
        return self.reference_line + every[:, :3], every[:, 3:6], every[:, 6:].reshape(-1, 3, 3)

    def _points(self, state) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each point's line position, rotation increment and frame-carried offset (N, 3) each."""
        q = self.beam.q.x.array if state is None else state[self.block]
        line, theta, frames = self._nodes_at(q)
        offset = np.einsum("nij,kj->nki", frames, self.offsets).reshape(-1, 3)
        return np.repeat(line, 3, axis=0), np.repeat(theta, 3, axis=0), offset

    def positions(self, state=None) -> np.ndarray:
        line, theta, offset = self._points(state)
        return line + rotated(theta, offset)

    def unknowns(self, state=None) -> Unknowns:
        _, theta, offset = self._points(state)
        return Unknowns(
            np.full(self.n_nodes, self.block), self.u_dofs, self.theta_dofs, rotated_derivative(theta, offset)
        )

    def values(self, owned, state=None) -> np.ndarray:
        v = owned[self.block]
        moved = self._gather(np.concatenate([v[self._u_local], v[self._theta_local]], axis=1))[
            self.beam_nodes
        ]
        du, dtheta = np.repeat(moved[:, :3], 3, axis=0), np.repeat(moved[:, 3:], 3, axis=0)
        jacobian = self.unknowns(state).jacobian
        return du + np.einsum("nij,nj->ni", jacobian, dtheta)

    def rotation_hessian(self, forces, state=None) -> np.ndarray:
        _, theta, offset = self._points(state)
        return rotated_second_derivative(theta, offset, forces)


class JoinedSurface(ContactSurface):
    """Parts (:class:`ContactSurface` s of distinct blocks, numbered as ``part.block``) as one
    surface: their nodes one part after the other, their cells renumbered."""

    def __init__(self, parts):
        self.parts = list(parts)
        if not self.parts:
            raise ValueError("a joined contact surface needs at least one part")
        self.comm = self.parts[0].comm
        self.blocks = 1 + max(p.block for p in self.parts)
        self.carried = any(p.carried for p in self.parts)
        self._starts = np.cumsum([0] + [p.n_nodes for p in self.parts])
        self.n_nodes = int(self._starts[-1])
        self.owned = np.concatenate([p.owned + s for p, s in zip(self.parts, self._starts, strict=False)])
        self.cells = np.vstack([p.cells + s for p, s in zip(self.parts, self._starts, strict=False)])
        self.material = np.vstack([p.material for p in self.parts])
        self.weights = np.concatenate([p.weights for p in self.parts])

    def state(self) -> list[np.ndarray]:
        out = [None] * self.blocks
        for p in self.parts:
            out[p.block] = p.state()[0]
        return out

    def positions(self, state=None) -> np.ndarray:
        return np.vstack([p.positions(state) for p in self.parts])

    def unknowns(self, state=None) -> Unknowns:
        parts = [p.unknowns(state) for p in self.parts]
        return Unknowns(
            *(np.concatenate([getattr(u, f) for u in parts]) for f in Unknowns.__dataclass_fields__)
        )

    def values(self, owned, state=None) -> np.ndarray:
        return np.vstack([p.values(owned, state) for p in self.parts])

    def rotation_hessian(self, forces, state=None) -> np.ndarray:
        return np.vstack(
            [
                p.rotation_hessian(forces[s : s + p.n_nodes], state)
                for p, s in zip(self.parts, self._starts, strict=False)
            ]
        )
