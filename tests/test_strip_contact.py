"""Contact between a beam's flat strip and itself, and between a shell and that strip.

The strip a flattened beam sweeps (:class:`~tapecoil.contact.surface.BeamStripSurface`) and a
shell's mid-surface joined into one contact surface, as the hybrid's coil is: beam spans laid
over each other and a shell strip laid over a beam span. Checked as the shell's own contact is
(``tests/test_self_contact.py``): a uniform penetration gives a uniform pressure; the forces sum
to zero; Newton's operator (the assembled part taken to the rotations by the chain rule, the
rotations' second derivative and the applied part) against central differences of the force;
2 ranks against 1.
"""

import math

import numpy as np
import pytest
from contact_checks import central_force_difference
from mpi4py import MPI
from petsc4py import PETSc

H, B, E = 1e-4, 0.02, 130e9
PENALTY = 0.01 * E * H / 0.005**2


def _beam(comm, spans, element=0.005):
    from tapecoil.config import config_from_dict
    from tapecoil.models.tape_beam import tape_beam

    config = config_from_dict({"tape": {"h": H, "R": 0.0151, "alpha": B / 0.0151}})
    return tape_beam(config, spans, element, flat_before=10.0, comm=comm)


def _strip(beam, block):
    from tapecoil.contact.surface import BeamStripSurface

    cells = np.arange(beam.mesh.topology.index_map(1).size_local, dtype=np.int32)
    offsets = np.array([[0.0, -B / 2, 0.0], [0.0, 0.0, 0.0], [0.0, B / 2, 0.0]])
    return BeamStripSurface(beam.model, cells, offsets, block=block)


def _shell(comm, start, length, along):
    from tapecoil.geometry.meshes import MeshResolution, create_strip_mesh
    from tapecoil.geometry.surfaces import StripGeometry
    from tapecoil.models.shell import NaghdiShell, Nodes, ShellMaterial

    strip = create_strip_mesh(comm, StripGeometry(math.inf, B, length, start=start), MeshResolution(2, along))
    model = NaghdiShell(strip, ShellMaterial(E, 0.3, H))
    return model, Nodes(model)


def _place_beam(beam, where):
    """Displace each node of the beam to ``where(X)`` (n, 3) of its reference points X."""
    m = beam.model
    m.q.x.array[m.node_u_dofs] = where(m.node_points) - m.node_points
    m.q.x.scatter_forward()


def test_a_beam_strip_laid_on_itself_presses_uniformly_and_in_balance():
    """Consistency: the second span of a beam laid over the first 0.9 h above it (shifted along
    by a fraction of an element, so that no point lies over an edge between cells): every
    point of both strips presses with k 0.1 h, and the forces sum to zero (equal and opposite)."""
    from tapecoil.contact.self_contact import SelfContact

    comm = MPI.COMM_WORLD
    beam = _beam(comm, [(0.0, 0.1), (1.0, 1.1)])
    _place_beam(beam, lambda X: X + np.where(X[:, :1] > 0.5, [-1.0 + 0.0013, 0.0, 0.9 * H], 0.0))
    surface = _strip(beam, 0)
    assert surface.weights.sum() == pytest.approx(2 * 0.1 * B, rel=1e-12)
    contact = SelfContact(surface, H, PENALTY, 0.0, 2 * H, exclusion=0.03)
    pairs = contact.pairs(contact.new_search())
    gaps = np.concatenate(comm.allgather(pairs.gap))
    pressure = np.concatenate(comm.allgather(-pairs.force / surface.weights[pairs.node]))
    # each span's points but those beyond the other's ends
    assert gaps.size >= 2 * 3 * (2 * 20 + 1) - 2 * 3 * 2
    assert gaps == pytest.approx(np.full(gaps.size, -0.1 * H), abs=1e-9 * H)
    assert pressure == pytest.approx(np.full(pressure.size, PENALTY * 0.1 * H), rel=1e-9)
    forces = comm.allreduce(contact.nodal_forces(pairs))
    assert np.abs(forces.sum(axis=0)).max() <= 1e-12 * np.abs(forces).sum()


def test_a_shell_laid_on_a_beam_strip_presses_uniformly_and_in_balance():
    """Consistency: a flat shell strip 0.9 h above a beam's flat strip, joined into one surface
    (the shell block 0, the beam block 1): a uniform pressure k 0.1 h on both, forces in
    balance."""
    from tapecoil.contact.self_contact import SelfContact
    from tapecoil.contact.surface import JoinedSurface, ShellSurface

    comm = MPI.COMM_WORLD
    beam = _beam(comm, [(0.0, 0.1)])
    _place_beam(beam, lambda X: X * np.array([1.0, 1.0, 0.0]))  # the line on the plane z = 0
    model, nodes = _shell(comm, 1.0, 0.1, 17)
    model.q.x.array[nodes.u_dofs] = np.tile([-1.0 + 0.0011, 0.0, 0.9 * H], (nodes.u_dofs.shape[0], 1))
    model.q.x.scatter_forward()
    surface = JoinedSurface([ShellSurface(model, nodes, block=0), _strip(beam, 1)])
    contact = SelfContact(surface, H, PENALTY, 0.0, 2 * H, exclusion=0.03)
    pairs = contact.pairs(contact.new_search())
    gaps = np.concatenate(comm.allgather(pairs.gap))
    kinds = np.concatenate(comm.allgather(pairs.node < surface.parts[0].n_nodes))
    assert kinds.any() and (~kinds).any()  # the shell's points and the strip's
    assert gaps == pytest.approx(np.full(gaps.size, -0.1 * H), abs=1e-9 * H)
    forces = comm.allreduce(contact.nodal_forces(pairs))
    assert np.abs(forces.sum(axis=0)).max() <= 1e-12 * np.abs(forces).sum()


def _layered(comm):
    """Three layers, as a hybrid's coil stacks them: a beam span, a second span over it and a
    shell strip over that, each about 0.9 h above the one beneath with a gentle wave, the
    beam's nodes turned by small rotation increments (a Newton iterate's); the joined contact
    with its term on the joint numbering of shell (block 0) and beam (block 1)."""
    from tapecoil.contact.self_contact import SelfContact
    from tapecoil.contact.surface import JoinedSurface, ShellSurface
    from tapecoil.contact.term import SelfContactTerm
    from tapecoil.core.numbering import joint_numbering

    beam = _beam(comm, [(0.0, 0.1), (1.0, 1.1)])

    def beam_place(X):
        upper = X[:, :1] > 0.5
        s = X[:, 0] - np.where(upper[:, 0], 1.0, 0.0)
        z = np.where(upper[:, 0], (0.9 + 0.05 * np.sin(60 * s)) * H, 0.02 * H * np.cos(40 * s))
        # shifted along and across by a fraction of a cell, so that no point lies over an edge
        # between cells (where the force's share among the nodes has the C0 surface's kink)
        shift = np.where(upper[:, 0], 1.0, 0.0)
        return np.column_stack([s + 0.0013 * shift, X[:, 1] + B / 12 * shift, z])

    _place_beam(beam, beam_place)
    m = beam.model
    theta = np.zeros((len(m.node_points), 3))
    theta[:, 0] = 0.01 * np.sin(30 * m.node_points[:, 0])  # a twist about the line
    theta[:, 1] = 2e-4 * np.cos(50 * m.node_points[:, 0])
    m.q.x.array[m.node_theta_dofs] = theta
    m.q.x.scatter_forward()
    model, nodes = _shell(comm, 2.0, 0.1, 17)
    X = nodes.reference.T
    s = X[:, 0] - 2.0
    u = np.column_stack([s + 0.0007, X[:, 1] - B / 7, (1.8 + 0.04 * np.sin(70 * s)) * H]) - X
    model.q.x.array[nodes.u_dofs] = u
    model.q.x.scatter_forward()
    surface = JoinedSurface([ShellSurface(model, nodes, block=0), _strip(beam, 1)])
    contact = SelfContact(surface, H, PENALTY, 0.05 * H, 2 * H, exclusion=0.03)
    numbering = joint_numbering([(model.W, []), (m.W, [])], comm)
    term = SelfContactTerm(contact, numbering)
    return model, m, contact, term


def _joint_vector(comm, model, beam_model):
    n = sum(V.dofmap.index_map.size_local * V.dofmap.index_map_bs for V in (model.W, beam_model.W))
    v = PETSc.Vec().createMPI((n, PETSc.DECIDE), comm=comm)
    v.set(0.0)
    return v


def _joint_matrix(comm, size):
    A = PETSc.Mat().createAIJ((size, size), comm=comm)
    A.setPreallocationNNZ((60, 60))
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    A.setUp()
    A.assemble()
    return A


def _set_joint(model, beam_model, vector) -> None:
    """Put a joint vector's values into the shell's and the beam's states."""
    values = vector.getArray(readonly=True)
    n0 = model.W.dofmap.index_map.size_local * model.W.dofmap.index_map_bs
    for f, part in ((model.q, values[:n0]), (beam_model.q, values[n0:])):
        f.x.array[: len(part)] = part
        f.x.scatter_forward()


def _get_joint(model, beam_model, vector) -> None:
    n0 = model.W.dofmap.index_map.size_local * model.W.dofmap.index_map_bs
    n1 = beam_model.W.dofmap.index_map.size_local * beam_model.W.dofmap.index_map_bs
    vector.setArray(np.concatenate([model.q.x.array[:n0], beam_model.q.x.array[:n1]]))


def test_the_joined_contact_operator_is_the_derivative_of_its_force():
    """Newton's operator of the shell-beam contact (the pairs' blocks taken to the beam's
    rotations by the chain rule, the rotations' second derivative times the forces, and the
    part applied through the nodal normals) against central differences of the force in a
    random direction of shell and beam dofs: exact to the differences' own error."""
    comm = MPI.COMM_WORLD
    model, beam_model, _contact, term = _layered(comm)
    x0 = _joint_vector(comm, model, beam_model)
    _get_joint(model, beam_model, x0)
    term.begin()
    pairs = term.current()
    assert comm.allreduce(len(pairs.node)) > 0
    A = _joint_matrix(comm, x0.getSizes())
    term.add_jacobian(A)
    A.assemble()
    rng = np.random.default_rng(3)
    d = x0.duplicate()
    d.setArray(rng.standard_normal(d.getLocalSize()) * 1e-4 * H)
    Ad = x0.duplicate()
    A.mult(d, Ad)
    assembled = Ad.copy()
    term.apply_coupling(d, Ad)

    def move(sign):
        x = x0.copy()
        x.axpy(sign, d)
        _set_joint(model, beam_model, x)

    fp = central_force_difference(term, move, x0)
    error = fp.copy()
    error.axpy(-1.0, Ad)
    assert Ad.norm() > 0
    assert error.norm() <= 1e-6 * Ad.norm()
    assembled.axpy(-1.0, fp)
    assert assembled.norm() >= 1e-5 * Ad.norm()  # the applied part matters

    # the applied part's transpose is its adjoint
    w = x0.duplicate()
    w.setArray(rng.standard_normal(w.getLocalSize()))
    Kd, Ktw = x0.duplicate(), x0.duplicate()
    Kd.set(0.0)
    Ktw.set(0.0)
    term.apply_coupling(d, Kd)
    term.apply_coupling(w, Ktw, transpose=True)
    assert w.dot(Kd) == pytest.approx(Ktw.dot(d), rel=1e-10)


def _layered_figures(comm):
    model, beam_model, contact, term = _layered(comm)
    x0 = _joint_vector(comm, model, beam_model)
    _get_joint(model, beam_model, x0)
    term.begin()
    b = x0.duplicate()
    b.set(0.0)
    term.add_residual(b)
    A = _joint_matrix(comm, x0.getSizes())
    term.add_jacobian(A)
    A.assemble()
    d = x0.duplicate()
    _set_joint_wave(model, beam_model, d)
    Ad = x0.duplicate()
    A.mult(d, Ad)
    term.apply_coupling(d, Ad)
    return contact.energy(term.current()), b.norm(), Ad.norm()


def _set_joint_wave(model, beam_model, d) -> None:
    """A smooth direction of shell and beam dofs, the same whatever the ranks."""
    from tapecoil.core import compat

    n0 = model.W.dofmap.index_map.size_local * model.W.dofmap.index_map_bs
    shell = np.zeros(n0)
    for i in range(3):
        space, dofs = compat.collapse(model.W.sub(0).sub(i))
        xs = space.tabulate_dof_coordinates()
        own = dofs < n0
        shell[dofs[own]] = 1e-3 * H * np.sin(40 * xs[own, 0] + 200 * xs[own, 1] + i)
    bm = beam_model
    n1 = bm.W.dofmap.index_map.size_local * bm.W.dofmap.index_map_bs
    beam = np.zeros(n1)
    for dofs, scale in ((bm.node_u_dofs, 1e-3 * H), (bm.node_theta_dofs, 1e-3)):
        own = dofs[:, 0] < n1
        beam[dofs[own]] = scale * np.sin(30 * bm.node_points[own, :1] + np.arange(3))
    d.setArray(np.concatenate([shell, beam]))


@pytest.mark.mpi
def test_two_ranks_assemble_the_joined_contact_as_one():
    comm = MPI.COMM_WORLD
    assert comm.size > 1
    parallel = _layered_figures(comm)
    serial = _layered_figures(MPI.COMM_SELF)
    assert parallel[0] > 0
    assert parallel == pytest.approx(serial, rel=1e-10)
