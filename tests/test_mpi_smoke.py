"""MPI smoke test: a distributed DOLFINx mesh and collective results (mpirun -n 2)."""

import pytest

pytestmark = pytest.mark.mpi


def test_distributed_mesh_collectives():
    import dolfinx
    import ufl
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    mesh = dolfinx.mesh.create_unit_square(comm, 8, 8)
    cells = mesh.topology.index_map(mesh.topology.dim)
    # every rank owns part of the mesh, and the parts add up to the whole
    assert cells.size_local > 0
    assert comm.allreduce(cells.size_local, op=MPI.SUM) == cells.size_global == 128
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ufl.dx(domain=mesh)))
    assert comm.allreduce(local, op=MPI.SUM) == pytest.approx(1.0, rel=1e-12)
    # a distributed vector: the global norm is the same as the serial one
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: x[0] + 2 * x[1])
    l2 = comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(u * u * ufl.dx)), op=MPI.SUM)
    assert l2 == pytest.approx(1 / 3 + 1 + 4 / 3, rel=1e-12)  # int (x + 2y)^2 over the unit square
