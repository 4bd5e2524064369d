"""The shell's sections that a window move placed from the beam, settled on the shell.

A beam's section placed rigidly at the shell's nodes (:func:`~tapecoil.models.window.carry_over`)
is not the shell's own equilibrium there. :func:`settle_placed` lets the sections a move placed,
the old window's edge and the old shell's element beside it find it among their neighbours,
where a motion in time would release that difference as a vibration; :func:`settle_at_rest`
settles a whole window of a tape at rest (a release). Both are one static solve of
:func:`settle`. :func:`settle_withdrawn` does the same for the beam's nodes that a move fitted
to the old shell's sections.
"""

from __future__ import annotations

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.core import jit
from tapecoil.core.dofs import global_scalar
from tapecoil.core.newton import SNESSolver
from tapecoil.models.nodes import Nodes

__all__ = ["settle", "settle_at_rest", "settle_placed", "settle_withdrawn"]

# settle_placed frees the old window's edge and this many of the old shell's elements beside it:
# the old edge was held to a rigid section by its tie, and its neighbours stood in equilibrium
# with it; the new shell's element across the edge pulls on them (docs/notes/hybrid.md, "The placed
# sections settled", has the root's reaction after a move with the edge, one and two elements)
SETTLED_OLD_ELEMENTS = 1


def settle_placed(hybrid, old_window: tuple[float, float], config) -> dict:
    """Settle the sections of ``hybrid``'s shell that a window move placed from the old beam
    (those outside ``old_window`` (start, end) [m], but for the tie's edge), the old window's
    edges and the old shell's SETTLED_OLD_ELEMENTS elements beside them (the edge was held to a
    rigid section by its tie): one static solve of the shell's energy for their dofs, every
    other dof held where the carry-over put it.

    A beam's section placed rigidly at the shell's nodes is not the shell's own equilibrium
    there: the shell's quadratic interpolation between sections placed exactly at its nodes
    strains it (on a coil, where an element spans a third of a radian of the hub on the default
    mesh and a radian on the coarse one). In a static solve the next step removes it; in time it
    would be released as a spurious vibration. Returns :func:`settle`'s figures."""
    old_start, old_end = old_window
    reach = SETTLED_OLD_ELEMENTS * hybrid.shell.element_length

    def placed(x, start, end, tol):
        free = (x < old_start - tol) | (x > old_end + tol)
        if start + tol < old_start:  # the old start edge is inside the new window
            free |= (x > old_start - tol) & (x < old_start + reach + tol)
        if old_end < end - tol:
            free |= (x < old_end + tol) & (x > old_end - reach - tol)
        return free

    return settle(hybrid, placed, config)


def settle_at_rest(hybrid, config) -> dict:
    """Settle every section of ``hybrid``'s shell but its window's two end edges (each tied to
    the beam, held to the hub or holding the free end where the guide left it): one static solve
    of the shell's energy, the beam held. For a tape at rest whose window has grown (a release):
    the sections placed from the beam strain the shell, and their settling moves the whole free
    part beyond the lift-off, which a band beside them alone cannot follow. Returns
    :func:`settle`'s figures."""
    return settle(hybrid, lambda x, start, end, tol: np.ones(x.shape, dtype=bool), config)


def settle(hybrid, choose, config) -> dict:
    """One static solve of ``hybrid``'s shell's energy for the dofs of the nodes that
    ``choose(x, start, end, tol)`` marks (a mask over the nodes' places x along the tape [m], the
    window (start, end) [m] and a tolerance [m]), but for the window's end edges; every other dof
    held where it is. Returns the strain energy [J] of the window before and after, the largest
    displacement [m] and the Newton iterations (collective); on a failed solve the state is kept
    and ``converged`` is False."""
    shell = hybrid.shell
    model = shell.model
    nodes = Nodes(model)
    (start, end), _ = shell.surface.xi_range
    x = nodes.xi[0]
    tol = 1e-9 * (1.0 + abs(end))
    free = choose(x, start, end, tol) & (x > start + tol) & (x < end - tol)
    strain = jit.form(model.strain_energy)
    before = global_scalar(strain, shell.comm)
    if shell.comm.allreduce(int(free.sum())) == 0:
        return {
            "strain_energy_placed": before,
            "strain_energy_settled": before,
            "moved": 0.0,
            "iterations": 0,
            "converged": True,
        }
    free_dofs = np.concatenate([nodes.u_dofs[free].ravel(), nodes.theta_dofs[free].ravel()])
    result, placed = _solve_for(
        model.q,
        free_dofs,
        shell.forms(),
        shell.bcs,
        config,
        prefix=f"{shell.name}_placed_",
        # an energy's minimum from a strained placement: a full Newton step can overshoot it
        defaults={"pc_type": "cholesky", "snes_linesearch_type": "bt"},
        state_scale=model.rounding_scale(),
    )
    change = model.q.x.array - placed.x.array
    moved = float(np.linalg.norm(change[nodes.u_dofs], axis=1).max(initial=0.0))
    hybrid.state_changed()
    return {
        "strain_energy_placed": before,
        "strain_energy_settled": global_scalar(strain, shell.comm),
        "moved": shell.comm.allreduce(moved, op=MPI.MAX),
        "iterations": int(result.iterations),
        "converged": bool(result.converged),
    }


def settle_withdrawn(hybrid, stretch: tuple[float, float], config) -> dict:
    """Settle the beam's nodes strictly inside ``stretch`` (start, end) [m], fitted by a window
    move to the old shell's sections (the shell turned into beam): one static solve of the beam's
    energy for their dofs, every other dof held (the tie's node and the old beam's beyond), the
    rotations then committed.

    A fitted node takes the rigid motion of the shell's section there; its line is the section's
    centroid. Where the section is not the beam's (in time its arc breathes, flattened a little
    here and less there), the centroid's place across the tape varies along it and the fitted
    line leans off the fitted frames: a transverse shear that the beam's large shear stiffness
    holds with many times the shell's strain energy of that stretch (docs/notes/hybrid.md, "Where the
    energy goes at a move"). Returns the beam's strain energy [J] before and after, the largest
    displacement [m] and the Newton iterations (collective); on a failed solve the fitted state
    is kept and ``converged`` is False."""
    beam = hybrid.beam
    model = beam.model
    comm = model.mesh.comm
    start, end = stretch
    tol = 1e-9 * (1.0 + abs(end))
    x = model.node_points[:, 0]
    free = (x > start + tol) & (x < end - tol)
    before = model.strain_energy()
    figures = {"strain_energy_fitted": before, "moved": 0.0, "iterations": 0, "converged": True}
    if comm.allreduce(int(free.sum())) == 0:
        return {**figures, "strain_energy_settled": before}
    free_dofs = np.concatenate([model.node_u_dofs[free].ravel(), model.node_theta_dofs[free].ravel()])
    result, fitted = _solve_for(
        model.q,
        free_dofs,
        beam.forms(),
        beam.bcs,
        config,
        prefix=f"{beam.name}_withdrawn_",
        # the rotations' Hessian is not symmetric away from equilibrium; a line search as for
        # the shell's placed sections
        defaults={"pc_type": "lu", "snes_linesearch_type": "bt"},
        state_scale=model.rounding_scale(),
        point_forces=beam.point_forces,
    )
    if not result.converged:
        return {
            **figures,
            "strain_energy_settled": before,
            "iterations": int(result.iterations),
            "converged": False,
        }
    change = model.q.x.array[model.node_u_dofs] - fitted.x.array[model.node_u_dofs]
    moved = float(np.linalg.norm(change, axis=1).max(initial=0.0))
    model.commit()
    hybrid.state_changed()
    return {
        "strain_energy_fitted": before,
        "strain_energy_settled": model.strain_energy(),
        "moved": comm.allreduce(moved, op=MPI.MAX),
        "iterations": int(result.iterations),
        "converged": True,
    }


def _solve_for(q, free_dofs, forms, bcs, config, *, prefix, defaults, state_scale, point_forces=()):
    """One static solve of ``forms`` (residual, Jacobian) for the dofs ``free_dofs`` of ``q``,
    every other dof held where it is (and ``bcs``), with ``config.solver``'s settings under
    ``prefix``; on a failed solve ``q`` is put back. Returns the solve's result and a Function
    holding the state it started from."""
    start = dolfinx.fem.Function(q.function_space)
    start.x.array[:] = q.x.array
    held = np.setdiff1d(np.arange(len(q.x.array), dtype=np.int32), free_dofs).astype(np.int32)
    solver = SNESSolver.from_config(
        *forms,
        q,
        [*bcs, dolfinx.fem.dirichletbc(start, held)],
        config.solver,
        prefix=prefix,
        defaults=defaults,
        state_scale=state_scale,
    )
    solver.point_forces = list(point_forces)
    result = solver.solve()
    solver.destroy()
    if not result.converged:
        q.x.array[:] = start.x.array
    q.x.scatter_forward()
    return result, start
