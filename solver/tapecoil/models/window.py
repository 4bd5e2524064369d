"""The hybrid's shell window moved along the tape, with the state carried over.

:func:`carry_over` sets the states of a new :class:`~tapecoil.models.hybrid_problem.HybridProblem`
from an old one of the same tape whose shell window lies elsewhere along it, at an accepted
step. The new hybrid is built by its caller with the same supports and loads (the thesis re-placed
its shell strip by hand between stages with an "import analysis"; here the program does it).
The beam's and the shell's nodes lie at the same points along the tape (the same element
length), so every transfer is made node by node, without interpolation along the tape:

- where the old hybrid had shell and the new one has shell, the new shell takes the old one's
  nodal values;
- where the old hybrid had beam and the new one has shell (the window grown into the beam),
  each section of the new shell is placed rigidly in the old beam's section frame at that point,
  with the shape of that beam's section (the arc, or the flattened strip), as a tie places its
  edge: phi = r + Q o, d = Q n, o and n the section's offsets and normals in the beam's
  reference frame, Q the node's frame relative to its reference;
- where the old hybrid had shell and the new one has beam (the window withdrawn from behind the
  ploy region), each node of the new beam takes the rigid motion that fits the old shell's
  section there best, in the shape of the new beam's section: r and Q minimising the sum over
  the section's nodes, weighted by their share of the width, of |p - r - Q o|^2 + l^2 |d - Q n|^2
  for Q (l a quarter of the width; the directors fix the turn about a flat section's line), and
  of |p - r - Q o|^2 for r. Its frames
  at the quadrature points are fitted the same way to the section there, the shell's nodes
  interpolated along the tape by its own quadratic shape functions, and their curvature,
  axial(Lambda^T Lambda'), is taken by a central difference of those fits;
- where both have beam, the new beam takes the old one's nodes, frames and curvatures;
- each tie takes the rotation of its end's section; a tie that the old hybrid had at the same
  node keeps its shape (and so the gaps through which it carries load), a new one takes its
  edge's shape as it is (:meth:`~tapecoil.models.interface.RigidSectionTie.keep_shape`), so that
  no penalty energy is stored by the carry-over itself. A new tie then carries no load until
  its gaps open, in the next solve.

A section carried between beam and shell keeps its place and its turn. The shell's section
deformation beyond the beam's shape is dropped where shell becomes beam, and the shell's own
interpolation error of a turned arc is added where beam becomes shell: the energy is conserved
where the section has the beam's shape (docs/notes/hybrid.md gives the measured figures).

The rates of a moving tape are carried over by :func:`~tapecoil.models.window_motion.carry_motion`,
and the sections a move placed settle by :mod:`~tapecoil.models.window_settling`.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from mpi4py import MPI
from scipy.spatial import cKDTree

from tapecoil.models.interface import section_shape
from tapecoil.models.nodes import Nodes

__all__ = ["carry_over", "full_shell"]

# the curvature of a fitted frame field by a central difference over this share of an element
DIFFERENCE_STEP = 1e-3


def _gathered(comm, *arrays) -> list[np.ndarray]:
    return [np.concatenate(comm.allgather(np.ascontiguousarray(a))) for a in arrays]


def _match(tree: cKDTree, points: np.ndarray, scale: float, what: str, comm) -> np.ndarray:
    """The indices of the tree's points at ``points``; refused on every rank when any is off."""
    distance, index = tree.query(points) if len(points) else (np.zeros(0), np.zeros(0, dtype=int))
    worst = comm.allreduce(float(distance.max(initial=0.0)), op=MPI.MAX)
    if worst > 1e-9 * scale:
        raise ValueError(f"carry over: {what} do not lie where the old hybrid's do (off by {worst:.3g} m)")
    return index


def window_of(hybrid) -> tuple[float, float]:
    """The shell window's ends along the tape [m]."""
    return hybrid.shell.surface.xi_range[0]


def _shape_of(hybrid, x: np.ndarray) -> np.ndarray:
    """For points ``x`` along the tape in ``hybrid``'s beam: True where its section is flat (the
    shape of the tie on that side of the window)."""
    start, end = window_of(hybrid)
    flat = np.zeros(len(x), dtype=bool)
    for edge, side in (("xi1_min", x <= start), ("xi1_max", x >= end)):
        tie = hybrid.ties.get(edge)
        if tie is not None and tie.section == "flat":
            flat |= side
    return flat


def _section_shape(geometry, xi: np.ndarray, centre: np.ndarray, flat: bool):
    """The section's offsets from the beam's line (n, 3) [m] and its normals (n, 3), in the
    beam's reference frame, at parameter points ``xi`` (2, n) whose beam nodes are at
    ``centre`` ((3,) or (n, 3) [m]): the arc as it is, or the strip laid flat (as the tie has them)."""
    centre = np.asarray(centre, dtype=float)
    ends = centre.T if centre.ndim == 2 else centre
    offsets, normals = section_shape(geometry.R, xi, ends, 1.0 if flat else 0.0)
    return offsets.T, normals.T


def _fit(points, directors, offsets, normals, weights, arm):
    """The rigid motion (r, Q) that fits p = r + Q o, d = Q n best (weighted least squares with
    the directors at lever ``arm`` [m]; Kabsch's construction)."""
    source = np.concatenate([offsets, offsets + arm * normals])
    target = np.concatenate([points, points + arm * directors])
    w = np.concatenate([weights, weights])
    source_mean, target_mean = w @ source / w.sum(), w @ target / w.sum()
    H = ((source - source_mean) * w[:, None]).T @ (target - target_mean)
    U, _, Vt = np.linalg.svd(H)
    sign = np.sign(np.linalg.det(Vt.T @ U.T))
    Q = Vt.T @ np.diag([1.0, 1.0, sign]) @ U.T
    # the line's place from the positions alone: a director off Q n (the shell's transverse
    # shear) would otherwise move it by the lever, and strain the beam along its line
    return weights @ (points - offsets @ Q.T) / weights.sum(), Q


class _ShellSections:
    """An old shell's nodes gathered on every rank, section by section along the tape: positions,
    directors and parameter points, interpolated along the tape by the shell's quadratic shape
    functions."""

    def __init__(self, shell, comm):
        nodes = Nodes(shell)
        q = shell.q.x.array
        xi, points, directors = _gathered(comm, nodes.xi.T, nodes.positions(q).T, nodes.directors(q).T)
        self.geometry = shell.strip.geometry
        tolerance = 1e-9 * (1.0 + np.abs(xi).max())  # far below a node spacing
        # sections: the nodes clustered by x (a mesh generator's coordinates of one section
        # differ in the last digits), then ordered across by xi_2; a node on several ranks
        # (shared) appears once per rank: one of them kept
        order = np.argsort(xi[:, 0], kind="stable")
        section = np.concatenate([[0], np.cumsum(np.diff(xi[order, 0]) > tolerance)])
        section_of = np.empty(len(xi), dtype=np.int64)
        section_of[order] = section
        order = np.lexsort((xi[:, 1], section_of))
        xi, points, directors, section_of = xi[order], points[order], directors[order], section_of[order]
        keep = np.concatenate([[True], (np.diff(section_of) > 0) | (np.abs(np.diff(xi[:, 1])) > tolerance)])
        xi, points, directors, section_of = xi[keep], points[keep], directors[keep], section_of[keep]
        starts = np.flatnonzero(np.concatenate([[True], np.diff(section_of) > 0]))
        across = len(xi) // len(starts)
        if across * len(starts) != len(xi) or (len(starts) - 1) % 2:
            raise ValueError("carry over: the shell's nodes do not form whole sections of quadratic elements")
        self.x = xi[starts, 0]
        self.xi2 = xi[:across, 1]
        self.points = points.reshape(len(starts), across, 3)
        self.directors = directors.reshape(len(starts), across, 3)
        # each node's share of the width: the quadratic elements' Simpson weights
        self.weights = np.zeros(across)
        for k in range(0, across - 1, 2):
            width = self.xi2[k + 2] - self.xi2[k]
            self.weights[k : k + 3] += width * np.array([1.0, 4.0, 1.0]) / 6
        self.arm = 0.25 * (self.xi2[-1] - self.xi2[0])

    def contains(self, x: np.ndarray, ends: bool = False) -> np.ndarray:
        """True for points ``x`` [m] inside the shell (its ends included with ``ends``)."""
        margin = (-1.0 if ends else 1.0) * 1e-9 * (1.0 + np.abs(self.x).max())
        return (x > self.x[0] + margin) & (x < self.x[-1] - margin)

    def section_at(self, x: float):
        """Positions and directors (across, 3) and parameter points (2, across) at ``x`` [m]."""
        k = min(max(int(np.searchsorted(self.x, x) - 1) // 2 * 2, 0), len(self.x) - 3)
        x0, x1, x2 = self.x[k : k + 3]
        shape = np.array(
            [
                (x - x1) * (x - x2) / ((x0 - x1) * (x0 - x2)),
                (x - x0) * (x - x2) / ((x1 - x0) * (x1 - x2)),
                (x - x0) * (x - x1) / ((x2 - x0) * (x2 - x1)),
            ]
        )
        points = np.einsum("k,kjc->jc", shape, self.points[k : k + 3])
        directors = np.einsum("k,kjc->jc", shape, self.directors[k : k + 3])
        directors /= np.linalg.norm(directors, axis=1)[:, None]
        return points, directors, np.vstack([np.full(len(self.xi2), x), self.xi2])

    def fit(self, x: float, centre: np.ndarray, flat: bool):
        """The rigid motion (r [m], Q) of the section at ``x`` about the beam node ``centre``."""
        points, directors, xi = self.section_at(x)
        offsets, normals = _section_shape(self.geometry, xi, centre, flat)
        return _fit(points, directors, offsets, normals, self.weights, self.arm)


def _frames_from_shell(sections, points, references, flat_of) -> tuple[np.ndarray, np.ndarray]:
    """Frames (n, 9) and curvatures (n, 3) at quadrature points ``points`` (n, 3) [m] of the new
    beam, whose reference frames there are ``references`` (n, 9), fitted to the old shell's
    sections (see the module)."""
    step = DIFFERENCE_STEP * np.min(np.diff(sections.x))
    frames, curvatures = [], []
    flat = flat_of(points[:, 0])
    for p, reference, is_flat in zip(points, references.reshape(-1, 3, 3), flat, strict=True):
        fitted = []
        for dx in (-step, 0.0, step):
            centre = p + np.array([dx, 0.0, 0.0])
            _, Q = sections.fit(centre[0], centre, is_flat)
            fitted.append(Q @ reference)
        F = fitted[1]
        dF = (fitted[2] - fitted[0]) / (2 * step)
        S = F.T @ dF
        frames.append(F.reshape(9))
        curvatures.append([(S[2, 1] - S[1, 2]) / 2, (S[0, 2] - S[2, 0]) / 2, (S[1, 0] - S[0, 1]) / 2])
    return np.array(frames).reshape(-1, 9), np.array(curvatures).reshape(-1, 3)


def _unwrapped_pitch(x: np.ndarray, rotations: np.ndarray, edge: float, edge_angle: float) -> np.ndarray:
    """The beam nodes' turns about the width axis (y) [rad], from their rotations (n, 3, 3) at
    points ``x`` (n,) [m] along the tape, unwrapped outwards from the window's ``edge`` [m]
    starting from ``edge_angle`` there (the shell's director angle theta_1 at that edge)."""
    pitch = np.arctan2(rotations[:, 0, 2], rotations[:, 2, 2]) if len(x) else np.zeros(0)
    out = np.empty_like(pitch)
    for side in (x <= edge, x > edge):
        order = np.flatnonzero(side)[np.argsort(np.abs(x[side] - edge), kind="stable")]
        out[order] = np.unwrap(np.concatenate([[edge_angle], pitch[order]]))[1:]
    return out


def full_shell(model) -> SimpleNamespace:
    """A full shell's state (a :class:`~tapecoil.models.shell.NaghdiShell` on a strip along the
    whole tape, a coiled tape's, say) as the old side of :func:`carry_over`: shell everywhere,
    no beam, no ties."""
    strip = model.strip
    return SimpleNamespace(
        shell=SimpleNamespace(model=model, strip=strip, surface=strip.geometry), beam=None, ties={}
    )


def carry_over(old, new) -> None:
    """Set ``new``'s shell, beam and ties from ``old``'s (see the module; collective). ``new``
    may be a full shell (:func:`full_shell`): its state is then the old shell's in the old
    window and placed by the old beam's sections elsewhere.

    Both hybrids are of the same tape along x, with the same element length and the same shell
    elements across; each tie's end a beam node. ``old`` must be at an accepted step (its
    rotation increments zero); it may be a full shell (:func:`full_shell`), whose state the new
    hybrid's beam then takes by fits wherever it lies. Where the two windows overlap the states
    are the old shell's; the new window may lie anywhere along the tape.

    The tape is straight in its reference (as the hybrids' tapes are): the central differences
    of the fitted frames take the reference frame at a quadrature point for the points a small
    step either side of it.
    """
    comm = old.shell.strip.mesh.comm
    beam, shell = old.beam.model if old.beam is not None else None, old.shell.model
    if beam is not None:
        theta = beam.q.x.array[beam.node_theta_dofs]
        if comm.allreduce(float(np.abs(theta).max(initial=0.0)), op=MPI.MAX) > 0.0:
            raise ValueError(
                "carry over: the old hybrid is not at an accepted step (its beam's rotation "
                "increments are not zero)"
            )
    # the old states, every rank's, node by node
    sections = _ShellSections(shell, comm)
    old_nodes = Nodes(shell)
    q_shell = shell.q.x.array
    shell_xi, shell_u, shell_theta = _gathered(
        comm, old_nodes.xi.T, q_shell[old_nodes.u_dofs], q_shell[old_nodes.theta_dofs]
    )
    if beam is not None:
        q_beam = beam.q.x.array
        beam_points, beam_u, beam_frames, beam_reference = _gathered(
            comm, beam.node_points, q_beam[beam.node_u_dofs], beam.node_frames, beam.node_reference_frames
        )
        points, old_frames, old_curvatures = _gathered(
            comm, *(beam.quadrature_values(name) for name in ("points", "frame_n", "curvature_n"))
        )
    else:
        beam_points, beam_u, points, old_frames, old_curvatures = (np.zeros((0, n)) for n in (3, 3, 3, 9, 3))
        beam_frames = beam_reference = np.zeros((0, 3, 3))
    # the tape's extent, from the old states gathered on every rank
    scale = 1.0 + max(float(np.abs(shell_xi).max(initial=0.0)), float(np.abs(beam_points).max(initial=0.0)))
    tolerance = 1e-9 * scale
    beam_tree = cKDTree(beam_points)
    rotations = beam_frames @ np.transpose(beam_reference, (0, 2, 1))  # Q = Lambda Lambda_0^T
    old_start, old_end = window_of(old)
    # where the new beam takes its state from the old shell: inside it, and at its ends too
    # when the old hybrid has no beam there
    fitted_ends = beam is None

    # the new shell: the old shell's nodes, then sections placed by the old beam
    new_model = new.shell.model
    nodes = Nodes(new_model)
    xi = nodes.xi.T
    q = new_model.q.x.array
    from_shell = (xi[:, 0] >= old_start - tolerance) & (xi[:, 0] <= old_end + tolerance)
    index = _match(cKDTree(shell_xi), xi[from_shell], scale, "the new shell's nodes", comm)
    q[nodes.u_dofs[from_shell]] = shell_u[index]
    q[nodes.theta_dofs[from_shell]] = shell_theta[index]
    placed = ~from_shell
    if comm.allreduce(int(placed.sum())) > 0:
        centre_line = beam_points[0, 1:]  # the beam's line across the tape (y, z), the same all along
        geometry = new.shell.strip.geometry
        flat = _shape_of(old, xi[placed, 0])
        centres = np.column_stack([xi[placed, 0], np.tile(centre_line, (int(placed.sum()), 1))])
        k = _match(beam_tree, centres, scale, "the new shell's sections", comm)
        for near, side in ((old_start, xi[placed, 0] < old_start), (old_end, xi[placed, 0] > old_end)):
            # the unbounded angle's branch: the old shell's at its edge on that side, continued
            # along the beam node by node (a coil turns its sections through many turns)
            edge = np.isclose(shell_xi[:, 0], near, rtol=0, atol=tolerance)
            pitch = _unwrapped_pitch(beam_points[:, 0], rotations, near, float(np.mean(shell_theta[edge, 1])))
            for is_flat in (False, True):
                pick = side & (flat == is_flat)
                if not pick.any():
                    continue
                where = np.flatnonzero(placed)[pick]
                offsets, normals = _section_shape(geometry, xi[where].T, centres[pick], is_flat)
                Q = rotations[k[pick]]
                position = centres[pick] + beam_u[k[pick]] + np.einsum("nij,nj->ni", Q, offsets)
                q[nodes.u_dofs[where]] = position - geometry.phi0(xi[where].T).T
                director = np.einsum("nij,nj->in", Q, normals)
                angles = new_model.angles_of(director, xi[where].T, rotation_near=pitch[k[pick]])
                q[nodes.theta_dofs[where]] = angles.T
    new_model.q.x.scatter_forward()
    if new.beam is None:
        return  # a full shell: no beam, no ties

    # the new beam's nodes: the old beam's, then fitted to the old shell's sections
    target = new.beam.model
    inside = sections.contains(target.node_points[:, 0], ends=fitted_ends)
    if len(beam_points) and not fitted_ends:
        # at an end of the old shell that no old beam node continues (the root of a window that
        # started there), the shell's section is the state's
        distance = beam_tree.query(target.node_points)[0] if len(target.node_points) else np.zeros(0)
        inside |= sections.contains(target.node_points[:, 0], ends=True) & (distance > tolerance)
    target.q.x.array[target.node_theta_dofs] = 0.0
    frames = target.node_reference_frames.copy()
    outside = ~inside
    k = _match(beam_tree, target.node_points[outside], scale, "the new beam's nodes", comm)
    target.q.x.array[target.node_u_dofs[outside]] = beam_u[k]
    frames[outside] = beam_frames[k]
    flat_new = _shape_of(new, target.node_points[:, 0])
    for i in np.flatnonzero(inside):
        centre = target.node_points[i]
        r, Q = sections.fit(centre[0], centre, flat_new[i])
        target.q.x.array[target.node_u_dofs[i]] = r - centre
        frames[i] = Q @ target.node_reference_frames[i]
    target.node_frames = frames
    target.q.x.scatter_forward()

    # the new beam's quadrature points: the old beam's, then fitted
    new_points = target.quadrature_values("points")
    new_frames = target.quadrature_values("frame_n")
    new_curvatures = target.quadrature_values("curvature_n")
    inside = sections.contains(new_points[:, 0], ends=fitted_ends)
    k = _match(cKDTree(points), new_points[~inside], scale, "the new beam's quadrature points", comm)
    new_frames[~inside], new_curvatures[~inside] = old_frames[k], old_curvatures[k]
    references = target.quadrature_values("frame_0")  # on every rank: its Expression is compiled collectively
    if inside.any():
        new_frames[inside], new_curvatures[inside] = _frames_from_shell(
            sections, new_points[inside], references[inside], lambda x: _shape_of(new, x)
        )
    target.set_quadrature_values(new_frames, new_curvatures)

    # the ties: their ends' section rotations
    for tie in new.ties.values():
        end = np.asarray(tie.end, dtype=float)
        if sections.contains(end[:1], ends=fitted_ends)[0]:
            _, Q = sections.fit(end[0], end, tie.section == "flat")
        else:
            Q = rotations[_match(beam_tree, end[None, :], scale, "a new tie's end", comm)[0]]
        tie.turned.value[:] = Q
    if old.beam is not None:  # a full shell's load parameter is its own phase's
        new.beam.committed_load = old.beam.committed_load
    new.set_load(new.beam.committed_load)
    for edge, tie in new.ties.items():
        kept = old.ties.get(edge)
        if (
            kept is not None
            and np.allclose(kept.end, tie.end, rtol=0, atol=tolerance)
            and kept.section == tie.section
        ):
            # the same tie as before: its kept shape, with the gaps through which it carries load
            tie.copy_shape(kept)
        else:
            tie.keep_shape()
    new.state_changed()
