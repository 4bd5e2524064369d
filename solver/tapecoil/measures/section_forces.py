"""The force the tape carries across its sections: the axial force N along the whole tape.

A section is cut between two columns of nodes (nodes of equal xi_1, the material coordinate
along the tape). The force that the part beyond the cut exerts on the part before it is the sum,
over the nodes before the cut, of the strain energy's derivative with respect to their
displacements: the strain energy of a cell does not change when the cell translates, so the
cells wholly before the cut add nothing to that sum and only the cells the cut passes through
remain. It needs no equilibrium and no external force (contact, pull, root) enters it, so it
measures the force in the tape independently of what loads it. N is that force's component
along the centre line's tangent at the cut, tension positive.

What N tests (physics brief Sec. 5): with frictionless contact and a uniform tape, N + M kappa -
U is the same all along the tape; in a flattened coil of mid-surface radius rho, M kappa - U =
(D b / 2)(1/rho^2 - 1/R^2) (Eq. 2.6), so T - N there is Eq. 2.6 at the local radius, T the pull.
"""

from __future__ import annotations

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.core import jit
from tapecoil.core.dofs import assemble_into


class SectionForces:
    """The axial force across every section between node columns of a tape (collective).

    ``model``: the :class:`~tapecoil.models.shell.NaghdiShell`; ``nodes``: its
    :class:`~tapecoil.models.nodes.Nodes`. The columns are the distinct xi_1 of the nodes,
    gathered once.
    """

    def __init__(self, model, nodes, comm=MPI.COMM_WORLD):
        self.model, self.nodes, self.comm = model, nodes, comm
        self.form = jit.form(ufl.derivative(model.strain_energy, model.q, model.dq))
        self.force = dolfinx.fem.Function(model.W)
        self.n_owned = nodes.space.dofmap.index_map.size_local
        xi1 = nodes.xi[0]
        # the columns: node xi_1 rounded well below the element length, the same on every rank
        scale = max(comm.allreduce(float(np.abs(xi1).max()) if xi1.size else 0.0, op=MPI.MAX), 1.0)
        key = np.round(xi1 / (1e-9 * scale)).astype(np.int64)
        columns = np.unique(np.concatenate(comm.allgather(np.unique(key))))
        self.column = np.searchsorted(columns, key)
        self.xi1 = columns * (1e-9 * scale)
        # the column's centre node: the one nearest xi_2 = 0 (the centre line), by rank-wide search
        xi2 = np.abs(nodes.xi[1])
        n = len(columns)
        best = np.full(n, np.inf)
        np.minimum.at(best, self.column[: self.n_owned], xi2[: self.n_owned])
        self.best_xi2 = np.min(comm.allgather(best), axis=0)
        self.centre = np.flatnonzero(
            np.isclose(xi2[: self.n_owned], self.best_xi2[self.column[: self.n_owned]])
        )

    def centre_positions(self, q: np.ndarray) -> np.ndarray:
        """Positions (n_columns, 3) of each column's centre-line node (collective, every rank)."""
        x = np.zeros((len(self.xi1), 3))
        count = np.zeros(len(self.xi1))
        owned = self.centre
        np.add.at(x, self.column[owned], self.nodes.positions(q)[:, owned].T)
        np.add.at(count, self.column[owned], 1.0)
        x = self.comm.allreduce(x, op=MPI.SUM)
        count = self.comm.allreduce(count, op=MPI.SUM)
        return x / count[:, None]

    def __call__(self) -> dict[str, np.ndarray]:
        """Per cut (between columns k and k + 1): ``xi1`` (the cut's material coordinate, the
        columns' midpoint) [m], ``force`` (n_cuts, 3) the force on the part before the cut [N],
        ``tangent`` (n_cuts, 3), ``axial_force`` N [N], and ``columns`` (n_cuts + 1, 3), the
        centre-line nodes' positions [m] (cut k lies between columns k and k + 1; on a coil the
        chord's midpoint lies inside the coil by the sagitta, so radii are read at the nodes)."""
        f = assemble_into(self.force, self.form)
        nodes, owned = self.nodes, slice(0, self.n_owned)
        per_column = np.zeros((len(self.xi1), 3))
        np.add.at(per_column, self.column[owned], f[nodes.u_dofs[owned]])
        per_column = self.comm.allreduce(per_column, op=MPI.SUM)
        # sum over the columns before each cut: the internal force the part beyond exerts
        cut_force = np.cumsum(per_column, axis=0)[:-1]
        x = self.centre_positions(self.model.q.x.array)
        chord = np.diff(x, axis=0)
        tangent = chord / np.linalg.norm(chord, axis=1)[:, None]
        # the strain energy's derivative on the part before the cut is minus the pull on it
        axial = -np.einsum("ij,ij->i", cut_force, tangent)
        return {
            "xi1": 0.5 * (self.xi1[:-1] + self.xi1[1:]),
            "force": -cut_force,
            "tangent": tangent,
            "axial_force": axial,
            "columns": x,
        }
