"""Derivatives of a node-to-surface gap measured along the surface's smoothed normal, on Q2 cells.

Geometry only. A point x (a contact node), the 9 nodes X_b of its partner cell, y = N_b(r) X_b
the cell's point closest to x (r its reference coordinates, each free or held on an edge by the
projection's clamp), and the smoothed normal n_s = m/|m|, m = N_b(r) n_b, from the nodes' unit
normals n_b (the normalised sum of the normals of the cells around each node: the Q2 surface is
only C0, and the cells' own normals jump across their edges). The gap, on the node's side s, is

    g = s (x - y) . n_s - h,

and the force on the pair's 30 displacement components q = (x, X_1, ..., X_9) is f B, with
f = dE/dg and B = s n_s (x) (1, -N_1, ..., -N_9) (equal and opposite: sum N_b = 1).

At fixed nodal normals (:func:`gap_derivatives`):

    dg = B . dq + c . dr,   c_j = s ((x - y) . dn_s/dr_j - dy/dr_j . n_s),
    H dr = L dq,            H_ij = dy/dr_i . dy/dr_j - (x - y) . d2y/dr_i dr_j,
                            L_i = (dy/dr_i, N_b,i (x - y) - N_b dy/dr_i)

(the closest-point condition (x - y) . dy/dr_i = 0 differentiated; a held coordinate has the
identity for its row of H and zero for its row of L), and B turns with r through n_s and N_b.
Along the smoothed normal c does not vanish as it would along the cell's own normal: n_s leans
off the cell's normal by up to half the angle between neighbouring cells, and that times the
cell's size is comparable to h.

The nodal normals move with the nodes of every cell around each node (:class:`NodalNormals`),
so the force of a pair also depends on the nodes of the cells around its partner cell (its
patch, up to 7 x 7 nodes). Left out of Newton's matrix, that dependence slows Newton to linear
convergence in the soft sliding modes of a coil's turns.

These formulas are computed pair by pair in the compiled kernels (``kernels.c``,
:mod:`tapecoil.contact.kernels`); this module keeps the surface's topology they need.
"""

from __future__ import annotations

import numpy as np

from tapecoil.contact import kernels


class NodalNormals:
    """The nodes' unit normals of a surface of Q2 cells and their derivatives with respect to the nodes.

    ``cells`` (Nc, 9) node indices of ``n_nodes`` nodes. A node's normal is the normalised sum of
    the unit normals (dy/dr_1 x dy/dr_2) of the cells around it, at the node; it depends on the
    nodes of those cells, its *neighbourhood* (``slot_start`` (N + 1) and ``slot_node``: node
    k's neighbours are ``slot_node[slot_start[k]:slot_start[k + 1]]``, sorted). The derivatives
    are 3 x 3 blocks dn_k/dX_j, one per slot.
    """

    def __init__(self, cells: np.ndarray, n_nodes: int):
        self.cells = np.ascontiguousarray(cells, dtype=np.int64)
        self.n_nodes = n_nodes
        # every (cell, node b, node a): node a is in node b's neighbourhood
        k = np.repeat(self.cells, 9, axis=1).ravel()
        j = np.tile(self.cells, (1, 9)).ravel()
        keys, self.slots = np.unique(k * n_nodes + j, return_inverse=True)
        self.slots = self.slots.astype(np.int64)
        self.slot_node = (keys % n_nodes).astype(np.int64)
        counts = np.bincount(keys // n_nodes, minlength=n_nodes)
        self.slot_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    @property
    def neighbourhood(self) -> tuple[np.ndarray, np.ndarray]:
        return self.slot_start, self.slot_node

    def normals(self, x: np.ndarray) -> tuple[np.ndarray, dict]:
        """Unit normals (N, 3) at the nodes at positions ``x`` (N, 3), and what their derivatives need."""
        return kernels.nodal_normals(self.cells, x)

    def derivatives(self, data: dict) -> np.ndarray:
        """dn_k/dX_j (slots, 3, 3) for every node k and node j of its neighbourhood, from
        :meth:`normals`' data."""
        return kernels.normal_derivatives(self.cells, self.slots, len(self.slot_node), data)
