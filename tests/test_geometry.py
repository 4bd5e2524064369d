"""gmsh strip and annulus: one surface for parameters and 3D, tags, presets, hub."""

import math
from pathlib import Path

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from tapecoil.config import MeshConfig, load_config
from tapecoil.geometry.meshes import (
    FREE_END,
    PRESETS,
    PRESETS_FILE,
    ROOT,
    SIDE_NEG,
    SIDE_POS,
    MeshResolution,
    create_strip_mesh,
    load_presets,
)
from tapecoil.geometry.surfaces import AnnulusGeometry, StripGeometry


def integrate(mesh, expr, measure):
    return mesh.comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(expr * measure)), op=MPI.SUM)


@pytest.fixture
def tape_mesh():
    cfg = load_config()
    geom = StripGeometry.from_config(cfg)
    return create_strip_mesh(MPI.COMM_WORLD, geom, MeshResolution(across=4, along=20, grading=2.0)), cfg


def test_presets():
    L = 0.5
    assert MeshResolution.from_config(MeshConfig(preset="default"), L) == MeshResolution(9, 125)
    coarse = MeshResolution.from_config(MeshConfig(preset="coarse"), L)
    fine = MeshResolution.from_config(MeshConfig(preset="fine"), L)
    assert coarse.along < 125 < fine.along and coarse.across < 9 < fine.across
    custom = MeshResolution.from_config(MeshConfig(preset="coarse", elements_across=7, element_size=0.01), L)
    assert (custom.across, custom.along) == (7, 50)


def test_presets_file():
    """meshes/presets.toml holds the presets, MeshConfig accepts exactly their names."""
    import dataclasses

    assert PRESETS == {"coarse": (4, 0.0125), "default": (9, 0.004), "fine": (18, 0.002)}
    allowed = next(f.metadata["allowed"] for f in dataclasses.fields(MeshConfig) if f.name == "preset")
    assert tuple(PRESETS) == allowed
    # in a source tree the package's file is the link to the project's meshes/presets.toml
    project = Path(__file__).resolve().parents[1] / "meshes" / "presets.toml"
    if PRESETS_FILE.is_symlink():
        assert PRESETS_FILE.resolve() == project.resolve()
    assert load_presets(project) == PRESETS


@pytest.mark.parametrize(
    "text",
    [
        "[coarse]\nelements_across = 0\nelement_size = 0.01\n",
        "[coarse]\nelements_across = 4.5\nelement_size = 0.01\n",
        "[coarse]\nelements_across = true\nelement_size = 0.01\n",
        "[coarse]\nelements_across = 4\nelement_size = -0.01\n",
        "[coarse]\nelements_across = 4\n",
        "[coarse]\nelements_across = 4\nelement_size = 0.01\ngrading = 2\n",
        "coarse = 4\n",
        "[coarse\n",
    ],
)
def test_broken_presets_file_is_refused(tmp_path, text):
    path = tmp_path / "presets.toml"
    path.write_text(text)
    with pytest.raises(RuntimeError, match="presets"):
        load_presets(path)


def test_element_lengths():
    assert MeshResolution(4, 40).element_lengths(0.5) == pytest.approx((0.0125, 0.0125))
    first, last = MeshResolution(4, 20, grading=2.0).element_lengths(0.5)
    assert last / first == pytest.approx(2.0)
    ratio = 2.0 ** (1 / 19)
    assert first * sum(ratio**i for i in range(20)) == pytest.approx(0.5)  # they fill the length


def test_strip_mesh_written_by_gmsh(tmp_path):
    """create_strip_mesh(msh=...) writes gmsh's model: the solver's mesh, in parameter coordinates."""
    import gmsh

    comm = MPI.COMM_WORLD
    path = Path(comm.bcast(str(tmp_path), root=0)) / "strip.msh"  # rank 0 writes it
    strip = create_strip_mesh(comm, StripGeometry(0.0151, 0.0356, 0.5), MeshResolution(3, 10), msh=path)
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        x = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)
    finally:
        gmsh.finalize()
    assert len(x) == strip.mesh.geometry.index_map().size_global == 4 * 11
    assert np.all(x[:, 2] == 0) and np.max(np.abs(x[:, 1])) == pytest.approx(0.0356 / 2, rel=1e-12)


@pytest.mark.mpi
def test_gmsh_failure_reaches_every_rank(tmp_path):
    """gmsh runs on rank 0 only; its failure is raised on every rank instead of leaving the others
    waiting for a mesh that never comes."""
    comm = MPI.COMM_WORLD
    blocker = Path(comm.bcast(str(tmp_path), root=0)) / "file"
    if comm.rank == 0:
        blocker.write_text("a file where a directory should be")
    comm.barrier()
    try:
        create_strip_mesh(
            comm, StripGeometry(0.0151, 0.0356, 0.5), MeshResolution(2, 4), msh=blocker / "a.msh"
        )
        outcome = None
    except Exception as exc:
        outcome = str(exc)
    outcomes = comm.allgather(outcome)  # gathered, so that a rank that went on fails too
    assert outcomes[0] is not None and "Unable to open file" in outcomes[0]
    assert outcomes == [outcomes[0]] * comm.size
    # gmsh is left usable: the next mesh is made as usual
    strip = create_strip_mesh(comm, StripGeometry(0.0151, 0.0356, 0.5), MeshResolution(2, 4))
    assert strip.mesh.topology.index_map(2).size_global == 8


def test_strip_parameter_domain_and_tags(tape_mesh):
    strip, cfg = tape_mesh
    mesh, tp = strip.mesh, cfg.tape
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=strip.facet_tags)
    assert integrate(mesh, 1.0, ufl.dx(domain=mesh)) == pytest.approx(tp.L * tp.b, rel=1e-12)
    for tag, length in ((ROOT, tp.b), (FREE_END, tp.b), (SIDE_NEG, tp.L), (SIDE_POS, tp.L)):
        assert integrate(mesh, 1.0, ds(tag)) == pytest.approx(length, rel=1e-12)
    x = mesh.geometry.x
    assert np.all(x[:, 0] >= -1e-14) and np.all(x[:, 0] <= tp.L + 1e-14)
    assert np.all(np.abs(x[:, 1]) <= tp.b / 2 + 1e-14)
    # the side centroids tell the sides apart: SIDE_NEG at xi_2 = -b/2
    xi = ufl.SpatialCoordinate(mesh)
    assert integrate(mesh, xi[1], ds(SIDE_NEG)) == pytest.approx(-tp.b / 2 * tp.L, rel=1e-12)


def test_strip_nodes_lie_on_the_cylinder(tape_mesh):
    """Parameter nodes mapped by phi0 are points of the arc of radius R about (y, z) = (0, R)."""
    strip, cfg = tape_mesh
    X = strip.geometry.phi0(strip.mesh.geometry.x.T)
    radius = np.hypot(X[1], X[2] - cfg.tape.R)
    assert np.allclose(radius, cfg.tape.R, rtol=1e-12)
    # 3D area of the mapped surface (sqrt det a0 = 1 for this isometric map)
    assert np.allclose(strip.geometry.phi0_inverse(X), strip.mesh.geometry.x[:, :2].T, atol=1e-14)


def test_grading(tape_mesh):
    strip, _ = tape_mesh
    x = np.unique(np.round(strip.mesh.geometry.x[:, 0], 12))
    gathered = np.unique(np.concatenate(MPI.COMM_WORLD.allgather(x)))
    steps = np.diff(gathered)
    assert steps[-1] / steps[0] == pytest.approx(2.0, rel=1e-6)  # last / first element length


def test_frame_matches_jacobian():
    geom = StripGeometry(0.0151, 0.0356, 0.5)
    xi = np.array([[0.1, 0.2], [-0.01, 0.015]])
    t1, t2, n0 = geom.frame(xi)
    assert np.allclose(np.einsum("in,in->n", t1, n0), 0) and np.allclose(np.einsum("in,in->n", t2, n0), 0)
    assert np.allclose(n0[:, 0], [0, -math.sin(-0.01 / 0.0151), math.cos(-0.01 / 0.0151)])
    eps = 1e-7
    fd = (geom.phi0(xi + np.array([[0.0], [eps]])) - geom.phi0(xi - np.array([[0.0], [eps]]))) / (2 * eps)
    assert np.allclose(geom.jacobian(xi)[:, 1], fd, atol=1e-8)


def test_annulus():
    geom = AnnulusGeometry(6.0, 10.0)
    strip = create_strip_mesh(MPI.COMM_WORLD, geom, MeshResolution(across=3, along=16))
    mesh = strip.mesh
    xi = ufl.SpatialCoordinate(mesh)
    # area of the annulus: integral of r over (angle, r)
    assert integrate(mesh, xi[1], ufl.dx(domain=mesh)) == pytest.approx(math.pi * (100 - 36), rel=1e-12)
    eps = 1e-7
    pts = np.array([[0.3, 5.0], [6.5, 9.0]])
    fd = (geom.phi0(pts + np.array([[eps], [0.0]])) - geom.phi0(pts - np.array([[eps], [0.0]]))) / (2 * eps)
    assert np.allclose(geom.jacobian(pts)[:, 0], fd, atol=1e-6)


def test_across_and_along_count_the_elements_on_the_edges_they_name():
    """``across`` elements along xi_2 (a tape's width), ``along`` along xi_1 (its length): on a
    rectangle 1 x 2 of parameters meshed 3 x 5, the nodes' distinct xi_2 are 4 and xi_1 are 6."""
    from tapecoil.geometry.surfaces import MappedSurface

    flat = MappedSurface(lambda xi, ops: (xi[0], xi[1], 0 * xi[0]), ((0.0, 1.0), (0.0, 2.0)))
    strip = create_strip_mesh(MPI.COMM_WORLD, flat, MeshResolution(across=3, along=5))
    x = np.concatenate(MPI.COMM_WORLD.allgather(strip.mesh.geometry.x[:, :2]))
    # Q1 geometry: the mesh's nodes are the elements' corners
    assert len(np.unique(np.round(x[:, 0], 12))) == 5 + 1
    assert len(np.unique(np.round(x[:, 1], 12))) == 3 + 1


@pytest.mark.parametrize(
    "arguments, message",
    [
        ((0, 10), r"across = 0 must be a positive integer \(elements along xi_2, across a tape's width\)"),
        ((4, -2), r"along = -2 must be a positive integer \(elements along xi_1"),
        ((4.0, 10), "across = 4.0 must be a positive integer"),
        ((True, 10), "across = True must be a positive integer"),
        ((4, "10"), "along = '10' must be a positive integer"),
        ((4, 10, 0.0), "grading = 0.0 must be a positive number"),
        ((4, 10, math.inf), "grading = inf must be a positive number"),
    ],
)
def test_a_resolution_that_is_no_element_count_is_refused(arguments, message):
    with pytest.raises(ValueError, match=message):
        MeshResolution(*arguments)
    assert MeshResolution(np.int64(4), 10, 2).across == 4  # numpy integers are counts too


def _physical_groups(path) -> dict[str, np.ndarray]:
    """Each physical group's name -> the coordinates (n, 3) of its nodes, read by gmsh itself."""
    import gmsh

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        groups = {}
        for dim, tag in gmsh.model.getPhysicalGroups():
            _, coords = gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)
            groups[gmsh.model.getPhysicalName(dim, tag)] = coords.reshape(-1, 3)
    finally:
        gmsh.finalize()
    return groups


@pytest.mark.parametrize(
    "surface, names",
    [
        # a tape's strip keeps the names of the tape's edges (ROOT ... SIDE_POS)
        (StripGeometry(0.0151, 0.0356, 0.5), ("strip", "root", "free_end", "side_neg", "side_pos")),
        # any other surface names them by the parameter bound each lies on (XI1_MIN ... XI2_MAX)
        (AnnulusGeometry(6.0, 10.0), ("surface", "xi1_min", "xi1_max", "xi2_min", "xi2_max")),
    ],
)
def test_the_mesh_files_name_the_edges_by_what_they_are(tmp_path, surface, names):
    """The physical groups of gmsh's model: each edge's name is on the parameter bound it says
    (the nodes in parameter coordinates: xi_1 first, xi_2 second)."""
    comm = MPI.COMM_WORLD
    path = Path(comm.bcast(str(tmp_path), root=0)) / "surface.msh"  # rank 0 writes it
    create_strip_mesh(comm, surface, MeshResolution(3, 8), msh=path)
    if comm.rank != 0:
        return
    groups = _physical_groups(path)
    assert set(groups) == set(names)
    (a0, a1), (b0, b1) = surface.xi_range
    whole, lo1, hi1, lo2, hi2 = names
    assert len(groups[whole]) == 4 * 9
    for name, coordinate, bound in ((lo1, 0, a0), (hi1, 0, a1), (lo2, 1, b0), (hi2, 1, b1)):
        assert np.allclose(groups[name][:, coordinate], bound, atol=1e-12), name
