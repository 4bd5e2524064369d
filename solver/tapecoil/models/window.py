"""The hybrid's shell window grown into its beam, with the state carried over.

:func:`carry_over` sets the states of a new :class:`~tapecoil.models.hybrid_problem.HybridProblem`
from an old one of the same tape whose shell window ends earlier, at an accepted step. The new
hybrid is built by its caller with the same supports and loads (the thesis re-placed its shell
strip by hand between stages with an "import analysis"; here the program does it):

- where the old hybrid had shell, the new shell takes the old one's nodal values;
- where the old hybrid had beam and the new one has shell, each section of the new shell is
  placed rigidly in the old beam's section frame at that point, as the tie places the edge:
  phi = r + Q (X - X_c), d = Q n0, Q the node's frame relative to its reference. The beam's and
  the shell's nodes lie at the same points along the tape (the same element length), so this
  is exact at every node, without interpolation;
- where both have beam, the new beam takes the old one's nodal values and its frames and
  curvatures at the quadrature points;
- the tie takes the rotation of the new end's section.

A section carried from beam to shell keeps its shape, so the transfer conserves the
configuration exactly and the energy where the beam is unstrained (the straight part of a tape
ahead of its ploy region, which carries no moment when its end is free). Where the beam is bent,
the shell's section then finds its own shape in the next solve.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from scipy.spatial import cKDTree

from tapecoil.models.nodes import Nodes

__all__ = ["carry_over"]


def _gathered(comm, *arrays) -> list[np.ndarray]:
    return [np.concatenate(comm.allgather(np.ascontiguousarray(a))) for a in arrays]


def _match(tree: cKDTree, points: np.ndarray, scale: float, what: str, comm) -> np.ndarray:
    """The indices of the tree's points at ``points``; refused on every rank when any is off."""
    distance, index = tree.query(points) if len(points) else (np.zeros(0), np.zeros(0, dtype=int))
    worst = comm.allreduce(float(distance.max(initial=0.0)), op=MPI.MAX)
    if worst > 1e-9 * scale:
        raise ValueError(f"carry over: {what} do not lie where the old hybrid's do (off by {worst:.3g} m)")
    return index


def carry_over(old, new) -> None:
    """Set ``new``'s shell, beam and tie from ``old``'s (see the module; collective).

    Both hybrids are of the same tape along x, with the shell from the root and the beam beyond,
    the same element length and the same shell elements across; ``new``'s window is at least as
    long as ``old``'s. ``old`` must be at an accepted step (its rotation increments zero).
    """
    comm = old.shell.strip.mesh.comm
    beam, shell = old.beam.model, old.shell.model
    theta = beam.q.x.array[beam.node_theta_dofs]
    if comm.allreduce(float(np.abs(theta).max(initial=0.0)), op=MPI.MAX) > 0.0:
        raise ValueError(
            "carry over: the old hybrid is not at an accepted step (its beam's rotation increments "
            "are not zero)"
        )
    old_window = old.shell.surface.xi_range[0][1]
    new_window = new.shell.surface.xi_range[0][1]
    if new_window < old_window:
        raise ValueError(
            f"carry over: the new window ({new_window} m) is shorter than the old ({old_window} m)"
        )
    scale = 1.0 + new.beam.mesh.comm.allreduce(
        float(np.abs(new.beam.model.node_points).max(initial=0.0)), op=MPI.MAX
    )

    # the old states, every rank's, node by node
    old_nodes = Nodes(shell)
    q_shell = shell.q.x.array
    shell_xi, shell_u, shell_theta = _gathered(
        comm,
        old_nodes.space.tabulate_dof_coordinates()[:, :2],
        q_shell[old_nodes.u_dofs],
        q_shell[old_nodes.theta_dofs],
    )
    q_beam = beam.q.x.array
    beam_points, beam_u, beam_frames, beam_reference = _gathered(
        comm, beam.node_points, q_beam[beam.node_u_dofs], beam.node_frames, beam.node_reference_frames
    )
    beam_tree = cKDTree(beam_points)
    rotations = beam_frames @ np.transpose(beam_reference, (0, 2, 1))  # Q = Lambda Lambda_0^T

    # the new shell: old shell nodes, then sections placed by the old beam
    new_model = new.shell.model
    nodes = Nodes(new_model)
    xi = nodes.space.tabulate_dof_coordinates()[:, :2]
    q = new_model.q.x.array
    from_shell = xi[:, 0] <= old_window + 1e-9 * scale
    index = _match(cKDTree(shell_xi), xi[from_shell], scale, "the new shell's nodes", comm)
    q[nodes.u_dofs[from_shell]] = shell_u[index]
    q[nodes.theta_dofs[from_shell]] = shell_theta[index]
    ahead = ~from_shell
    if comm.allreduce(int(ahead.sum())) > 0:
        # the branch of the unbounded angle: the old shell's at its tied edge
        edge = np.isclose(shell_xi[:, 0], old_window, rtol=0, atol=1e-9 * scale)
        rotation_near = float(np.mean(shell_theta[edge, 1]))
        geometry = new.shell.strip.geometry
        X = geometry.phi0(xi[ahead].T) if ahead.any() else np.zeros((3, 0))
        centroid = np.asarray(new.tie.end, dtype=float)[1:]
        sections = np.column_stack([xi[ahead, 0], np.tile(centroid, (int(ahead.sum()), 1))])
        k = _match(beam_tree, sections, scale, "the new shell's sections", comm)
        if ahead.any():  # a rank may hold none of them
            Q = rotations[k]
            offset = X.T - sections
            position = sections + beam_u[k] + np.einsum("nij,nj->ni", Q, offset)
            q[nodes.u_dofs[ahead]] = position - X.T
            normals = geometry.frame(xi[ahead].T)[2]  # (3, n)
            director = np.einsum("nij,jn->in", Q, normals)
            angles = new_model.angles_of(director, xi[ahead].T, rotation_near=rotation_near)
            q[nodes.theta_dofs[ahead]] = angles.T
    new_model.q.x.scatter_forward()

    # the new beam: nodes, then frames and curvatures at the quadrature points
    target = new.beam.model
    k = _match(beam_tree, target.node_points, scale, "the new beam's nodes", comm)
    target.q.x.array[target.node_u_dofs] = beam_u[k]
    target.q.x.array[target.node_theta_dofs] = 0.0
    target.node_frames = beam_frames[k].copy()
    target.q.x.scatter_forward()
    points, frames, curvatures = _gathered(
        comm, *(beam.quadrature_values(name) for name in ("points", "frame_n", "curvature_n"))
    )
    new_points = target.quadrature_values("points")
    k = _match(cKDTree(points), new_points, scale, "the new beam's quadrature points", comm)
    target.set_quadrature_values(frames[k], curvatures[k])

    # the tie: the new end's section rotation
    end = _match(beam_tree, np.asarray(new.tie.end, dtype=float)[None, :], scale, "the new tie's end", comm)[
        0
    ]
    new.tie.turned.value[:] = rotations[end]
    new.beam.committed_load = old.beam.committed_load
    new._set_load(old.beam.committed_load)
