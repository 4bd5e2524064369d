"""The shell's numpy side: director frames and angles at parameter points, node-wise state views.

What sets a state from positions and directors (clamps, rigid rotations, the root on the hub)
and what reads one node by node (contact, predictors), without UFL. The functions that take
the shell first are also its methods (``model.angles_of(d, xi)``).
"""

from __future__ import annotations

import numpy as np

from tapecoil.models.director import angles_from_director

# ``shell``/``model`` below: the NaghdiShell these functions serve as its methods, read, never
# imported (the shell imports them)


def director_frame_numpy(shell, xi: np.ndarray):
    """The director frame (e1, e2, e3) and reference angles (2, n) at parameter points."""
    local = shell.strip.geometry.frame(xi)
    if shell.director_frame == "local":
        return local, np.zeros((2, xi.shape[1]))
    n = xi.shape[1]
    frame = tuple(np.tile(e[:, None], n) for e in np.eye(3))
    n0 = local[2]
    return frame, np.vstack([-np.arcsin(np.clip(n0[1], -1, 1)), np.arctan2(n0[0], n0[2])])


def angles_of(shell, d: np.ndarray, xi: np.ndarray, rotation_near: float = 0.0) -> np.ndarray:
    """Unknown angles theta (2, n) that give the directors d (3, n) at parameter points xi.

    The unbounded theta_1 is taken on the branch nearest ``rotation_near`` [rad].
    """
    frame, ref = director_frame_numpy(shell, xi)
    return angles_from_director(d, frame, theta1_near=ref[1] + rotation_near) - ref


class Nodes:
    """Node-wise numpy views of a shell state: positions, directors and the W-dofs behind them.

    All components of u and theta live on the same Q2 nodes; ``space`` is the scalar Q2 space on
    those nodes (local and ghost, in its own order) and ``u_dofs`` (n, 3), ``theta_dofs`` (n, 2)
    give the W-dof of each component at each node. Computations on these arrays are rank-local and,
    done on ghosts as on owners from the same values, give every rank the same values.
    """

    def __init__(self, model):
        from tapecoil.core import compat

        W = model.W
        spaces_maps = [compat.collapse(W.sub(0).sub(i)) for i in range(3)]
        spaces_maps += [compat.collapse(W.sub(1).sub(i)) for i in range(2)]
        self.space = spaces_maps[0][0]
        xi = self.space.tabulate_dof_coordinates()
        for space, _ in spaces_maps[1:]:  # the same node order in every collapsed component
            if not np.array_equal(space.tabulate_dof_coordinates(), xi):
                raise RuntimeError("collapsed shell components do not share their node order")
        self.u_dofs = np.column_stack([m for _, m in spaces_maps[:3]])
        self.theta_dofs = np.column_stack([m for _, m in spaces_maps[3:]])
        if self.u_dofs.shape != (xi.shape[0], 3) or self.theta_dofs.shape != (xi.shape[0], 2):
            raise RuntimeError(f"unexpected collapsed dof maps {self.u_dofs.shape}, {self.theta_dofs.shape}")
        self.xi = xi[:, :2].T.copy()
        self.reference = model.strip.geometry.phi0(self.xi)
        self.frame, self.theta_ref = director_frame_numpy(model, self.xi)

    def positions(self, q: np.ndarray) -> np.ndarray:
        """Mid-surface positions (3, n) for the W-dof array ``q``."""
        return self.reference + q[self.u_dofs].T

    def directors(self, q: np.ndarray) -> np.ndarray:
        """Unit directors (3, n) for the W-dof array ``q``."""
        t0, t1 = self.theta_ref + q[self.theta_dofs].T
        e1, e2, e3 = self.frame
        return np.cos(t0) * np.sin(t1) * e1 - np.sin(t0) * e2 + np.cos(t0) * np.cos(t1) * e3
