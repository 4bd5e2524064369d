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
"""

from __future__ import annotations

import numpy as np
import scipy.sparse

from tapecoil.contact.projection import Q2_TENSOR, _lagrange2, q2_basis


def q2_hessian(ref: np.ndarray) -> np.ndarray:
    """Second reference derivatives (n, 9, 2, 2) of the Q2 shape functions at points ``ref`` (n, 2)."""
    lx, dx = _lagrange2(ref[:, 0])
    ly, dy = _lagrange2(ref[:, 1])
    second = np.array([4.0, -8.0, 4.0])[:, None] * np.ones_like(ref[:, 0])
    i, j = Q2_TENSOR.T
    out = np.empty((ref.shape[0], 9, 2, 2))
    out[:, :, 0, 0] = (second[i] * ly[j]).T
    out[:, :, 1, 1] = (lx[i] * second[j]).T
    out[:, :, 0, 1] = out[:, :, 1, 0] = (dx[i] * dy[j]).T
    return out


def _cross_matrix(v: np.ndarray) -> np.ndarray:
    """[v]_x (..., 3, 3): [v]_x w = v x w."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _projector(n: np.ndarray, length: np.ndarray) -> np.ndarray:
    """(I - n n^T) / length (..., 3, 3): the derivative of v/|v| at v = length n."""
    return (np.eye(3) - n[..., :, None] * n[..., None, :]) / length[..., None, None]


def gap_derivatives(
    x: np.ndarray, X: np.ndarray, nodal: np.ndarray, ref: np.ndarray, held: np.ndarray, side: np.ndarray
) -> dict[str, np.ndarray]:
    """The gap's derivatives for P pairs at fixed nodal normals (module docstring).

    ``x`` (P, 3) the nodes, ``X`` (P, 9, 3) the partner cells' nodes, ``nodal`` (P, 9, 3) their
    unit normals, ``ref`` (P, 2) the closest points, ``held`` (P, 2) the coordinates held on an
    edge, ``side`` (P,). Returns ``B`` (P, 30), ``dg`` (P, 30) the gap's gradient, ``dB``
    (P, 30, 30) dB_a/dq_b, and ``dg_dm`` (P, 3), ``dB_dm`` (P, 30, 3): the derivatives with
    respect to m = N_b n_b.
    """
    P = x.shape[0]
    N, dN = q2_basis(ref)
    y = np.einsum("pb,pbi->pi", N, X)
    tangents = np.einsum("pbj,pbi->pji", dN, X)
    second = np.einsum("pbjk,pbi->pjki", q2_hessian(ref), X)
    r = x - y
    m = np.einsum("pb,pbi->pi", N, nodal)
    dm = np.einsum("pbj,pbi->pji", dN, nodal)
    length = np.linalg.norm(m, axis=1)
    n = m / length[:, None]
    turn = _projector(n, length)  # dn_s/dm
    dn = np.einsum("pik,pjk->pji", turn, dm)  # dn_s/dr_j
    e = side[:, None] * n
    shape = np.concatenate([np.ones((P, 1)), -N], axis=1)
    B = (shape[:, :, None] * e[:, None, :]).reshape(P, 30)

    H = np.einsum("pji,pki->pjk", tangents, tangents) - np.einsum("pi,pjki->pjk", r, second)
    L = shape[:, None, :, None] * tangents[:, :, None, :]
    L[:, :, 1:] += dN.transpose(0, 2, 1)[:, :, :, None] * r[:, None, None, :]
    L = L.reshape(P, 2, 30)
    L[held] = 0.0
    H = np.where(held[:, :, None] | held[:, None, :], 0.0, H)
    H[:, 0, 0] = np.where(held[:, 0], 1.0, H[:, 0, 0])
    H[:, 1, 1] = np.where(held[:, 1], 1.0, H[:, 1, 1])
    dr = np.linalg.solve(H, L)

    c = side[:, None] * (np.einsum("pi,pji->pj", r, dn) - np.einsum("pji,pi->pj", tangents, n))
    dg = B + np.einsum("pj,pja->pa", c, dr)
    dB_dr = np.empty((P, 2, 10, 3))
    dB_dr[:, :, 0] = side[:, None, None] * dn
    dB_dr[:, :, 1:] = (
        -N[:, None, :, None] * side[:, None, None, None] * dn[:, :, None, :]
        - dN.transpose(0, 2, 1)[:, :, :, None] * e[:, None, None, :]
    )
    dB = np.einsum("pja,pjb->pab", dB_dr.reshape(P, 2, 30), dr)
    dg_dm = side[:, None] * np.einsum("pi,pij->pj", r, turn)
    dB_dm = side[:, None, None, None] * shape[:, :, None, None] * turn[:, None, :, :]
    return {
        "B": B,
        "dg": dg,
        "dB": dB,
        "dg_dm": dg_dm,
        "dB_dm": dB_dm.reshape(P, 30, 3),
    }


class NodalNormals:
    """The nodes' unit normals of a surface of Q2 cells and their derivatives with respect to the nodes.

    ``cells`` (Nc, 9) node indices. A node's normal is the normalised sum of the unit normals
    (dy/dr_1 x dy/dr_2) of the cells around it, at the node. Each cell's *patch* is the nodes of
    every cell that shares a node with it (``patch`` (Nc, K), padded with -1): all that the
    normals of its nodes depend on.
    """

    def __init__(self, cells: np.ndarray):
        self.cells = cells
        n_cells = len(cells)
        self.gradients = q2_basis(Q2_TENSOR / 2.0)[1]  # (9 nodes, 9 shape functions, 2)
        node_cells: dict[int, list[int]] = {}
        for c, row in enumerate(cells):
            for node in row:
                node_cells.setdefault(int(node), []).append(c)
        patches = []
        for row in cells:
            around = sorted({c for node in row for c in node_cells[int(node)]})
            patches.append(np.unique(cells[around]))
        width = max(len(p) for p in patches)
        self.patch = np.full((n_cells, width), -1, dtype=np.int64)
        for c, p in enumerate(patches):
            self.patch[c, : len(p)] = p
        # the map from the cells' blocks dnu_c(b)/dX_a (the normal of cell c at its node b) to
        # the blocks dn_b/dX_k of each cell's nodes b over its patch k: a sum over the cells
        # around b
        rows, cols = [], []
        for c, row in enumerate(cells):
            position = {int(node): k for k, node in enumerate(patches[c])}
            for b_local, node in enumerate(row):
                for other in node_cells[int(node)]:
                    b_other = int(np.flatnonzero(cells[other] == node)[0])
                    for a in range(9):
                        k = position[int(cells[other, a])]
                        rows.append((c * 9 + b_local) * width + k)
                        cols.append((other * 9 + b_other) * 9 + a)
        self._gather = scipy.sparse.csr_matrix(
            (np.ones(len(rows)), (rows, cols)), shape=(n_cells * 9 * width, n_cells * 81)
        )

    def normals(self, x: np.ndarray) -> tuple[np.ndarray, dict]:
        """Unit normals (N, 3) at the nodes at positions ``x`` (N, 3), and what their derivatives need."""
        t = np.einsum("bak,cai->cbki", self.gradients, x[self.cells])  # (Nc, 9, 2, 3)
        T = np.cross(t[:, :, 0], t[:, :, 1])
        T_length = np.linalg.norm(T, axis=2)
        nu = T / T_length[:, :, None]
        total = np.zeros_like(x)
        np.add.at(total, self.cells.ravel(), nu.reshape(-1, 3))
        total_length = np.linalg.norm(total, axis=1)
        normals = total / np.maximum(total_length, 1e-300)[:, None]
        return normals, {"t": t, "nu": nu, "T_length": T_length, "normals": normals, "length": total_length}

    def derivatives(self, data: dict) -> np.ndarray:
        """dn_b/dX_k (Nc, 9, K, 3, 3) for each cell's nodes b over its patch k, from :meth:`normals`' data."""
        t, nu = data["t"], data["nu"]
        n_cells = len(self.cells)
        # dT/dX_a = -dN_a/dr_1 [t_2]_x + dN_a/dr_2 [t_1]_x (T = t_1 x t_2), per cell, node b, node a
        dT = (
            -self.gradients[None, :, :, 0, None, None] * _cross_matrix(t[:, :, 1])[:, :, None]
            + self.gradients[None, :, :, 1, None, None] * _cross_matrix(t[:, :, 0])[:, :, None]
        )
        node = self.cells
        outer = _projector(data["normals"][node], data["length"][node])  # dn_b/dM_b
        inner = _projector(nu, data["T_length"])  # dnu/dT
        blocks = np.matmul(np.matmul(outer, inner)[:, :, None], dT)  # (Nc, 9, 9, 3, 3)
        width = self.patch.shape[1]
        gathered = self._gather @ blocks.reshape(n_cells * 81, 9)
        return gathered.reshape(n_cells, 9, width, 3, 3)
