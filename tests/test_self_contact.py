"""Contact of a surface with itself: Q2 projection, the buffered search, the penalty's assembly.

The assembly is checked on a flat strip folded in two, its upper half laid over the lower one
at a prescribed separation: a consistency check of the contact's force and matrix (no solve).
"""

import math

import numpy as np
import pytest
from contact_checks import central_force_difference
from mpi4py import MPI

from tapecoil.contact.projection import CandidateSearch, closest_points, q2_basis


def test_q2_basis_is_basix_quadrilateral_order():
    import basix

    element = basix.create_element(basix.ElementFamily.P, basix.CellType.quadrilateral, 2)
    points = np.array([[0.2, 0.7], [0.9, 0.1], [0.5, 0.5]])
    N, dN = q2_basis(points)
    reference = element.tabulate(1, points)
    assert np.allclose(N, reference[0, :, :, 0], atol=1e-14)
    assert np.allclose(dN[:, :, 0], reference[1, :, :, 0], atol=1e-13)
    assert np.allclose(dN[:, :, 1], reference[2, :, :, 0], atol=1e-13)


def _cylinder_cell(radius, angle0, angle1, y0, y1):
    """Q2 cell nodes on a cylinder about the y axis (basix order)."""
    import basix

    ref = basix.create_element(basix.ElementFamily.P, basix.CellType.quadrilateral, 2).points
    a = angle0 + ref[:, 0] * (angle1 - angle0)
    y = y0 + ref[:, 1] * (y1 - y0)
    return np.column_stack([radius * np.cos(a), y, radius * np.sin(a)])


def test_closest_point_on_a_curved_cell_is_the_radial_projection():
    r, h = 0.0127, 1e-4
    cell = _cylinder_cell(r, 0.0, 0.2, 0.0, 0.01)
    angles = np.array([0.03, 0.1, 0.17])
    points = np.column_stack([(r + h) * np.cos(angles), [0.002, 0.005, 0.008], (r + h) * np.sin(angles)])
    found = closest_points(points, np.repeat(cell[None], 3, axis=0))
    # the Q2 arc of 0.2 rad is off the circle by about r (0.2)^4 / 512 = 4e-8 m
    assert found["distance"] == pytest.approx(np.full(3, h), abs=1e-7)
    radial = points / np.linalg.norm(points[:, [0, 2]], axis=1)[:, None]
    radial[:, 1] = 0.0
    assert np.abs(np.einsum("pi,pi->p", found["direction"], radial)) == pytest.approx(np.ones(3), abs=1e-5)


def test_search_finds_the_sheet_above_and_not_its_own_neighbourhood():
    """Two parallel sheets of 3 x 1 cells, h apart, one material strip folded over itself."""
    import basix

    h = 1e-4
    ref = basix.create_element(basix.ElementFamily.P, basix.CellType.quadrilateral, 2).points
    nodes, cells, material = [], [], []
    for sheet, z in ((0, 0.0), (1, h)):
        for i in range(3):
            x = 0.01 * (i + ref[:, 0])
            cell = np.column_stack([x, 0.01 * ref[:, 1], np.full(9, z)])
            start = len(nodes)
            nodes.extend(cell)
            # material coordinate: the fold puts the upper sheet 1 m further along the strip
            material.extend(np.column_stack([x + sheet * 1.0, 0.01 * ref[:, 1]]))
            cells.append(np.arange(start, start + 9))
    nodes, cells, material = np.array(nodes), np.array(cells), np.array(material)
    search = CandidateSearch(cells, material, exclusion=4e-4, reach=1.1 * h, buffer=2 * h)
    query = np.arange(len(nodes))
    node, cell = search.candidates(nodes, query)
    lower = cells[:3].ravel()
    # every candidate partner lies on the other sheet
    assert np.all((node < 27) == (cell >= 3))
    assert set(np.unique(node[node < 27])) == set(lower)
    # within half the buffer the list is kept; beyond, searched again
    assert search.valid_for(nodes + 0.4 * h, query) and not search.valid_for(nodes + 1.1 * h, query)


def test_search_keeps_every_cell_with_a_node_in_reach_and_clear_of_the_query():
    """The candidate list against its definition, pair by pair, on a wound strip of Q2 cells
    (three turns 1.5 h apart) queried for a subset of its nodes: every (node, cell) with a
    node of the cell within the search radius of the node, whose bounding sphere comes within
    reach + buffer of it and whose material box lies at least the exclusion away."""
    import basix

    h, turns, along = 1e-4, 3, 60
    ref = basix.create_element(basix.ElementFamily.P, basix.CellType.quadrilateral, 2).points
    nodes, cells, material = [], [], []
    for k in range(turns * along):
        s = (k + ref[:, 0]) / along  # turns of the spiral
        angle, y = 2 * np.pi * s, 0.004 * ref[:, 1]
        radius = 0.01 + 1.5 * h * s
        cells.append(np.arange(len(nodes), len(nodes) + 9))
        nodes.extend(np.column_stack([radius * np.cos(angle), y, radius * np.sin(angle)]))
        material.extend(np.column_stack([s * 2 * np.pi * 0.01, y]))
    nodes, cells, material = np.array(nodes), np.array(cells), np.array(material)
    reach, buffer, exclusion = 1.1 * h, 2 * h, 1e-3
    search = CandidateSearch(cells, material, exclusion=exclusion, reach=reach, buffer=buffer)
    query = np.arange(0, len(nodes), 3)
    node, cell = search.candidates(nodes, query)
    found = set(zip(node.tolist(), cell.tolist(), strict=True))
    assert len(found) == len(node)

    xyz = nodes[cells]
    span = np.linalg.norm(xyz[:, :, None, :] - xyz[:, None, [0, 3], :], axis=-1).max()
    radius = reach + buffer + 0.5 * span
    centre = xyz[:, 8]
    sphere = np.linalg.norm(xyz - centre[:, None, :], axis=2).max(axis=1)
    lower, upper = material[cells].min(axis=1), material[cells].max(axis=1)
    expected = set()
    for q in query:
        near = np.linalg.norm(xyz - nodes[q], axis=2).min(axis=1) <= radius
        clear = np.linalg.norm(nodes[q] - centre, axis=1) - sphere <= reach + buffer
        box = np.linalg.norm(np.maximum(np.maximum(lower - material[q], material[q] - upper), 0.0), axis=1)
        expected.update((int(q), int(c)) for c in np.flatnonzero(near & clear & (box >= exclusion)))
    assert found == expected
    # the turns' neighbours are found: each queried node of a middle turn has cells on both sides
    assert len(expected) > len(query)


@pytest.fixture(scope="module")
def folded():
    """A flat strip 0.2 m x 0.02 m whose second half is folded over its first at 0.9 h.

    The upper half is shifted by a third of a cell along and across, so that no node lies over
    an edge of the cells beneath: there the partner changes from cell to cell, and the force's
    share among the partner's nodes has a kink (that of the C0 surface's shape functions).
    """
    from tapecoil.contact.self_contact import SelfContact
    from tapecoil.contact.surface import ShellSurface
    from tapecoil.contact.term import SelfContactTerm, block_numbering
    from tapecoil.geometry.meshes import MeshResolution, create_strip_mesh
    from tapecoil.geometry.surfaces import StripGeometry
    from tapecoil.models.shell import NaghdiShell, Nodes, ShellMaterial

    L, b, h, E = 0.2, 0.02, 1e-4, 130e9
    strip = create_strip_mesh(MPI.COMM_WORLD, StripGeometry(math.inf, b, L), MeshResolution(4, 40))
    model = NaghdiShell(strip, ShellMaterial(E, 0.3, h))
    nodes = Nodes(model)
    X = nodes.reference
    s = X[0]
    upper = s > L / 2
    folded_x = np.where(upper, L - s + L / 120, s)
    folded_y = X[1] + np.where(upper, b / 12, 0.0)
    folded_z = np.where(upper, 0.9 * h, 0.0)
    u = np.vstack([folded_x, folded_y, folded_z]) - X
    model.q.x.array[nodes.u_dofs] = u.T
    penalty = 0.01 * E * h / (L / 40) ** 2
    contact = SelfContact(ShellSurface(model, nodes), h, penalty, 0.0, 2 * h, exclusion=0.03)
    term = SelfContactTerm(contact, block_numbering(model.W, []))
    return model, nodes, contact, term, penalty, h


def test_folded_strip_pressure_is_uniform_and_forces_balance(folded):
    """Consistency: a uniform penetration 0.1 h gives a uniform pressure k 0.1 h on both layers,
    and the contact forces sum to zero (equal and opposite)."""
    model, _, contact, term, k, h = folded
    pairs = term.current()
    gaps = np.concatenate(MPI.COMM_WORLD.allgather(pairs.gap))
    assert gaps.size > 0
    assert gaps == pytest.approx(np.full(gaps.size, -0.1 * h), abs=1e-9 * h)
    pressure = -pairs.force / contact.weights[pairs.node]
    pressure = np.concatenate(MPI.COMM_WORLD.allgather(pressure))
    assert pressure == pytest.approx(np.full(pressure.size, k * 0.1 * h), rel=1e-9)
    b = model.q.x.petsc_vec.duplicate()
    b.set(0.0)
    term.add_residual(b)
    f = np.zeros((contact.n_nodes, 3))
    values = b.getArray()
    start, _ = b.getOwnershipRange()
    owned_nodes = contact.surface.u_dofs[contact.owned] - start
    f[contact.owned] = values[owned_nodes]
    total = MPI.COMM_WORLD.allreduce(f.sum(axis=0))
    scale = MPI.COMM_WORLD.allreduce(np.abs(f).sum())
    assert scale > 0
    assert np.abs(total).max() <= 1e-12 * scale
    b.destroy()


def contact_matrix(model, term):
    """The contact term's assembled matrix alone, on the shell's matrix pattern."""
    import dolfinx.fem.petsc
    import ufl

    mass = ufl.inner(model.dq, ufl.TrialFunction(model.W)) * model.dx
    A = dolfinx.fem.petsc.create_matrix(dolfinx.fem.form(mass))
    A.zeroEntries()
    A.assemble()
    term.add_jacobian(A)
    A.assemble()
    return A


def test_contact_jacobian_is_the_derivative_of_its_force(folded):
    """Newton's operator for the contact (the assembled matrix plus the part applied through the
    nodal normals) against central differences of the force, in a random direction: exact, to
    the differences' own truncation and round-off (measured 2e-8 at perturbations of 1e-3 h).
    The assembled part alone leaves out the turning of the smoothed normals with the nodes
    around the partner cells (0.26 % here)."""

    model, _, _, term, _, h = folded
    q0 = model.q.x.array.copy()
    A = contact_matrix(model, term)
    rng = np.random.default_rng(3)
    direction = model.q.x.petsc_vec.duplicate()
    direction.setArray(rng.standard_normal(direction.getLocalSize()) * 1e-3 * h)
    Ad = direction.duplicate()
    A.mult(direction, Ad)
    assembled = Ad.copy()
    term.apply_coupling(direction, Ad)

    def move(sign):
        model.q.x.array[:] = q0
        model.q.x.petsc_vec.axpy(sign, direction)
        model.q.x.scatter_forward()

    fp = central_force_difference(term, move, direction)
    error = fp.copy()
    error.axpy(-1.0, Ad)
    assert error.norm() <= 1e-6 * Ad.norm()
    assembled.axpy(-1.0, fp)
    assert assembled.norm() >= 1e-4 * Ad.norm()  # the applied part matters
    for obj in (A, direction, Ad, assembled, fp, error):
        obj.destroy()


def test_contact_coupling_transpose_is_the_adjoint(folded):
    """<K^T w, v> = <w, K v> for the applied part K, in random directions (what a trust region's
    steepest descent uses)."""
    from tapecoil.contact.term import SelfContactTerm, block_numbering

    model, _, contact, _, _, _ = folded
    term = SelfContactTerm(contact, block_numbering(model.W, []))  # its own matrix pattern
    A = contact_matrix(model, term)
    rng = np.random.default_rng(5)
    v, w = model.q.x.petsc_vec.duplicate(), model.q.x.petsc_vec.duplicate()
    v.setArray(rng.standard_normal(v.getLocalSize()))
    w.setArray(rng.standard_normal(w.getLocalSize()))
    Kv, Ktw = v.duplicate(), v.duplicate()
    Kv.set(0.0)
    Ktw.set(0.0)
    term.apply_coupling(v, Kv)
    term.apply_coupling(w, Ktw, transpose=True)
    assert Kv.norm() > 0
    assert w.dot(Kv) == pytest.approx(Ktw.dot(v), rel=1e-12)
    for obj in (A, v, w, Kv, Ktw):
        obj.destroy()


def test_nodal_normals_derivatives_against_central_differences():
    """dn_k/dX_j over each node's neighbourhood, on a wavy 4 x 3 grid of Q2 cells, against
    central differences; a node outside k's neighbourhood does not move k's normal."""
    from tapecoil.contact.linearisation import NodalNormals
    from tapecoil.contact.projection import Q2_TENSOR

    nx, ny = 4, 3
    I, J = np.meshgrid(np.arange(2 * nx + 1), np.arange(2 * ny + 1), indexing="ij")
    ids = I * (2 * ny + 1) + J
    grid = [(i, j) for i in range(nx) for j in range(ny)]
    cells = np.array([[ids[2 * i + a, 2 * j + b] for a, b in Q2_TENSOR] for i, j in grid])
    x = np.column_stack([I.ravel(), J.ravel(), 0.3 * np.sin(I.ravel()) * np.cos(0.7 * J.ravel())]) * 1e-3
    field = NodalNormals(cells, len(x))
    normals, data = field.normals(x)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    D = field.derivatives(data)
    start, neighbours = field.neighbourhood
    step = 1e-9
    worst = 0.0
    for node in (ids[4, 3], ids[1, 0], ids[8, 6]):  # interior, free edge, corner
        for comp in range(3):
            plus, minus = x.copy(), x.copy()
            plus[node, comp] += step
            minus[node, comp] -= step
            fd = (field.normals(plus)[0] - field.normals(minus)[0]) / (2 * step)
            for k in range(len(x)):
                slot = start[k] + np.flatnonzero(neighbours[start[k] : start[k + 1]] == node)
                exact = D[slot[0], :, comp] if len(slot) else np.zeros(3)
                worst = max(worst, np.abs(exact - fd[k]).max() / np.abs(fd).max())
    assert worst <= 1e-6


def _folded_energy_and_force(comm):
    """Penalty energy, the norm of the contact force and that of the contact Jacobian's action
    (assembled and applied parts) on a smooth direction, for the folded strip on ``comm``."""

    from tapecoil.contact.self_contact import SelfContact
    from tapecoil.contact.surface import ShellSurface
    from tapecoil.contact.term import SelfContactTerm, block_numbering
    from tapecoil.geometry.meshes import MeshResolution, create_strip_mesh
    from tapecoil.geometry.surfaces import StripGeometry
    from tapecoil.models.shell import NaghdiShell, Nodes, ShellMaterial

    L, b, h, E = 0.2, 0.02, 1e-4, 130e9
    strip = create_strip_mesh(comm, StripGeometry(math.inf, b, L), MeshResolution(4, 40))
    model = NaghdiShell(strip, ShellMaterial(E, 0.3, h))
    nodes = Nodes(model)
    s = nodes.reference[0]
    # a gentle wave on the upper layer, so that the penetration varies along the strip
    z = np.where(s <= L / 2, 0.0, (0.9 + 0.05 * np.sin(40 * s)) * h)
    u = np.vstack([np.where(s <= L / 2, s, L - s), nodes.reference[1], z]) - nodes.reference
    model.q.x.array[nodes.u_dofs] = u.T
    model.q.x.scatter_forward()
    contact = SelfContact(
        ShellSurface(model, nodes), h, 0.01 * E * h / (L / 40) ** 2, 0.05 * h, 2 * h, exclusion=0.03
    )
    term = SelfContactTerm(contact, block_numbering(model.W, []))
    b_vec = model.q.x.petsc_vec.duplicate()
    b_vec.set(0.0)
    term.add_residual(b_vec)
    norm = b_vec.norm()
    A = contact_matrix(model, term)
    direction = model.q.x.petsc_vec.duplicate()
    direction.set(0.0)
    n_owned = nodes.space.dofmap.index_map.size_local
    wave = np.sin(60 * s + 300 * nodes.reference[1])[:n_owned]
    values = direction.getArray()
    values[nodes.u_dofs[:n_owned]] = 1e-3 * h * wave[:, None] * np.array([0.3, -0.5, 1.0])
    direction.setArray(values)
    action = direction.duplicate()
    A.mult(direction, action)
    term.apply_coupling(direction, action)
    action_norm = action.norm()
    for obj in (b_vec, A, direction, action):
        obj.destroy()
    return contact.energy(contact.pairs(contact.new_search())), norm, action_norm


@pytest.mark.mpi
def test_two_ranks_assemble_the_contact_as_one():
    assert MPI.COMM_WORLD.size > 1
    parallel = _folded_energy_and_force(MPI.COMM_WORLD)
    serial = _folded_energy_and_force(MPI.COMM_SELF)
    assert parallel[0] > 0
    assert parallel == pytest.approx(serial, rel=1e-10)


def test_a_flat_strip_does_not_touch_itself():
    """A flat strip of long, narrow cells: a node beside a cell of its own section, just beyond
    the exclusion and in the cell's plane, is not over that cell and touches nothing (it was
    once taken for a node sunk a whole thickness into it, and the coarse benchmark with 8
    elements across could not be flattened)."""
    from tapecoil.contact.self_contact import SelfContact
    from tapecoil.contact.surface import ShellSurface
    from tapecoil.geometry.meshes import MeshResolution, create_strip_mesh
    from tapecoil.geometry.surfaces import StripGeometry
    from tapecoil.models.shell import NaghdiShell, Nodes, ShellMaterial

    L, b, h, E = 0.2, 0.02, 1e-4, 130e9
    # cells 25 mm along and 2.5 mm across: a node one cell beside a cell lies well within the
    # cell's bounding sphere, so the search offers the pair
    strip = create_strip_mesh(MPI.COMM_WORLD, StripGeometry(math.inf, b, L), MeshResolution(8, 8))
    model = NaghdiShell(strip, ShellMaterial(E, 0.3, h))
    nodes = Nodes(model)
    buffer = 2 * h
    contact = SelfContact(ShellSurface(model, nodes), h, 1e12, 0.05 * h, buffer, exclusion=4 * (h + buffer))
    search = contact.new_search()
    offered, _ = search.candidates(contact.positions(), contact.owned)
    assert MPI.COMM_WORLD.allreduce(offered.size) > 0
    pairs = contact.pairs(search)
    assert MPI.COMM_WORLD.allreduce(pairs.node.size) == 0
    assert contact.energy(pairs) == 0.0


def test_the_matrix_pattern_is_renewed_when_old_pairs_outnumber_the_live_ones(folded):
    """The couplings of pairs that have come apart leave the matrix once they outnumber those
    of the live pairs (counted here from the pairs themselves, over both ranks): the upper
    layer slid by two cells, so that every node has a new partner, twice more. No renewal
    while nothing has converged in between, nor while the pattern holds only live pairs."""
    from tapecoil.contact.term import SelfContactTerm, block_numbering

    model, nodes, contact, _, _, _ = folded
    comm = MPI.COMM_WORLD
    q0 = model.q.x.array.copy()
    term = SelfContactTerm(contact, block_numbering(model.W, []))
    assert term.begin() is False
    held, live = set(), set()

    def jacobian():
        nonlocal live
        pairs = term.current()
        live = set(zip(pairs.node.tolist(), pairs.cell.tolist(), strict=True))
        held.update(live)
        contact_matrix(model, term).destroy()

    jacobian()
    assert term.begin() is False  # a retry from the same converged state
    upper = nodes.reference[0] > 0.1
    renewed = []
    for shift in (0.01, 0.02, 0.03):
        model.q.x.array[nodes.u_dofs[upper, 0]] = q0[nodes.u_dofs[upper, 0]] + shift
        model.q.x.scatter_forward()
        contact.accept()
        stale, alive = comm.allreduce(np.array([len(held - live), len(live)]), op=MPI.SUM)
        renewed.append(term.begin())
        assert renewed[-1] is bool(stale > alive)
        if renewed[-1]:
            held.clear()
        jacobian()
    model.q.x.array[:] = q0
    model.q.x.scatter_forward()
    contact.accept()
    assert renewed == [False, True, False] and term.pattern_renewals == 1


def test_a_retry_forgets_the_partners_kept(folded):
    """Consistency: within a solve a node keeps its partner cell while its closest point stays
    inside it; a retry of the step (no state converged since) keeps none and starts from the
    closest cells, as a run restarted from the converged state does. Deployments on the coarse
    mesh that stopped with every cut-back failing went on when restarted from the state they
    stopped at (docs/notes/coiling.md); with the partners forgotten on a retry, they went on unstopped."""
    _, _, _, term, _, _ = folded
    term.begin()
    pairs = term.current()
    assert MPI.COMM_WORLD.allreduce(pairs.node.size) > 0
    assert MPI.COMM_WORLD.allreduce(int((term._memory >= 0).sum())) > 0  # kept within the solve
    term.begin()  # no state converged in between: a retry
    assert np.all(term._memory == -1)
