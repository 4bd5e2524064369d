"""The compatibility layer on the installed DOLFINx (serial and under mpirun -n 2)."""

import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tapecoil.core import compat


def _rectangle_mesh(comm, lx=2.0, ly=0.5):
    import gmsh

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        if comm.rank == 0:
            gmsh.model.add("rect")
            surf = gmsh.model.occ.addRectangle(0, 0, 0, lx, ly)
            gmsh.model.occ.synchronize()
            gmsh.model.addPhysicalGroup(2, [surf], tag=1)
            left = [
                c
                for _, c in gmsh.model.getBoundary([(2, surf)], oriented=False)
                if abs(gmsh.model.occ.getCenterOfMass(1, c)[0]) < 1e-12
            ]
            gmsh.model.addPhysicalGroup(1, left, tag=7)
            gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.1)
            gmsh.model.mesh.generate(2)
        return compat.model_to_mesh(gmsh.model, comm, 0, gdim=2)
    finally:
        gmsh.finalize()


def _check_rectangle(comm):
    import dolfinx
    import ufl
    from mpi4py import MPI

    mesh, cell_tags, facet_tags = _rectangle_mesh(comm)
    area = comm.allreduce(
        dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ufl.dx(domain=mesh))), op=MPI.SUM
    )
    assert area == pytest.approx(1.0, rel=1e-12)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    left = comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ds(7))), op=MPI.SUM)
    assert left == pytest.approx(0.5, rel=1e-12)
    assert comm.allreduce(cell_tags.values.size, op=MPI.SUM) == mesh.topology.index_map(2).size_global
    return mesh


def test_version_supported():
    assert compat.DOLFINX_VERSION >= (0, 9)


def test_gmsh_model_to_mesh_serial():
    from mpi4py import MPI

    _check_rectangle(MPI.COMM_SELF)


def test_interpolation_points_and_vector():
    import dolfinx
    from mpi4py import MPI

    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 2, 2)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2))
    pts = compat.interpolation_points(V)
    assert pts.shape == (6, 2)
    b = compat.create_vector(V)
    assert b.getSize() == V.dofmap.index_map.size_global
    b.destroy()


@pytest.mark.mpi
def test_gmsh_model_to_mesh_distributed():
    from mpi4py import MPI

    mesh = _check_rectangle(MPI.COMM_WORLD)
    assert mesh.topology.index_map(2).size_local > 0  # rank 0 built it, every rank got a share
    assert np.all(np.isfinite(mesh.geometry.x))


def _mixed_space(comm):
    import basix.ufl
    import dolfinx

    mesh = dolfinx.mesh.create_unit_square(comm, 3, 2, dolfinx.mesh.CellType.quadrilateral)
    cell = mesh.basix_cell()
    P = basix.ufl.element("Lagrange", cell, 2, shape=(3,))
    T = basix.ufl.element("Lagrange", cell, 2, shape=(2,))
    return dolfinx.fem.functionspace(mesh, basix.ufl.mixed_element([P, T]))


def _check_collapse(W):
    import dolfinx

    parent = dolfinx.fem.Function(W)
    parent.x.array[:] = np.arange(parent.x.array.size)
    for sub in ((0,), (0, 2), (1,), (1, 1)):
        space = W
        for i in sub:
            space = space.sub(i)
        V, dofs = compat.collapse(space)
        n = (V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts) * V.dofmap.index_map_bs
        assert dofs.dtype == np.int32 and dofs.shape == (n,)  # flat, one parent dof per dof of V
        assert len(np.unique(dofs)) == n and dofs.max() < parent.x.array.size
        if len(sub) == 1:  # the map agrees with DOLFINx's own collapse of a sub-function
            assert np.array_equal(parent.sub(sub[0]).collapse().x.array, parent.x.array[dofs])
    # the five scalar components of the shell share one node order
    xi = [compat.collapse(W.sub(i).sub(j))[0].tabulate_dof_coordinates() for i, j in ((0, 0), (0, 2), (1, 1))]
    assert all(np.array_equal(x, xi[0]) for x in xi)


def test_collapse_map_is_flat():
    from mpi4py import MPI

    _check_collapse(_mixed_space(MPI.COMM_SELF))


@pytest.mark.mpi
def test_collapse_map_is_flat_distributed():
    from mpi4py import MPI

    _check_collapse(_mixed_space(MPI.COMM_WORLD))


def test_offscreen_rendering(tmp_path):
    pyvista = pytest.importorskip("pyvista")
    compat.start_offscreen_rendering()
    plotter = pyvista.Plotter(off_screen=True, window_size=(160, 120))
    plotter.add_mesh(pyvista.Sphere(), color="red")
    image = plotter.screenshot(str(tmp_path / "sphere.png"), return_img=True)
    plotter.close()
    assert image.shape[:2] == (120, 160)
    assert (image[..., 0] > image[..., 2] + 50).any()  # the red sphere, not a blank picture


def _xvfb_serving(display: str) -> list[int]:
    """Process ids of the Xvfb processes on this machine that serve ``display``."""
    pids = []
    for entry in Path("/proc").iterdir():
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
        except (OSError, ValueError):
            continue
        if argv and argv[0].endswith(b"Xvfb") and display.encode() in argv:
            pids.append(int(entry.name))
    return pids


@pytest.mark.skipif(shutil.which("Xvfb") is None, reason="no Xvfb here")
def test_private_xvfb_dies_with_its_process():
    # Two processes at once get servers of their own, and a process killed outright (no
    # clean-up of its own can run) leaves no server behind.
    script = (
        "import time; from tapecoil.core import compat;"
        " print(compat.start_private_xvfb(), flush=True); time.sleep(60)"
    )
    owners = [
        subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True) for _ in range(2)
    ]
    try:
        displays = [owner.stdout.readline().strip() for owner in owners]
        assert all(d.startswith(":") for d in displays) and displays[0] != displays[1]
        assert all(len(_xvfb_serving(d)) == 1 for d in displays)
    finally:
        for owner in owners:
            owner.send_signal(signal.SIGKILL)
            owner.wait()
    deadline = time.monotonic() + 10
    while any(_xvfb_serving(d) for d in displays) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(_xvfb_serving(d) for d in displays)
