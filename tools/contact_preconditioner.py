"""Newton's linear system of a coil on its own turns: preconditioners against the factorisation.

Reads a coiling checkpoint of a run with ``contact.turns = "surface"`` (a results directory's
stowed/, any rank count), builds the coiling solver's Newton operator at the checkpoint's
state (the shell, the hub, the pairs between the turns and their part through the nodal
normals) and solves one system with it (the residual there, or a random right-hand side
where the state is converged) by GMRES to a relative residual 1e-8 with:

- ``lu``: the factorised assembled matrix (what the solver does);
- ``local``: the factorised matrix without the pairs' couplings between a node and its partner
  cell (each pair keeps its node's and its cell's own blocks): the shell's pattern, whose
  factorisation is the strip's alone;
- ``lumped`` (one rank): the factorised matrix with each pair's partner cell collapsed onto its
  node nearest the closest point (a pair couples two nodes instead of a node and nine);
- ``twolevel``: ``local`` with a coarse correction: the pairs' normal direction on hat
  functions along the tape (spacing ``--spacing`` cells of the coil's nodes) times 1 and the
  coordinate across (``--across`` functions), the coarse matrix Z^T A Z by a sparse triple
  product, applied multiplicatively (coarse, local, coarse);
- ``sectors`` (one rank): ``local``, then an additive Schwarz correction on angular sectors of
  the coil through all its turns (``--sectors`` of them, each widened by ``--overlap`` of its
  width on either side, factorised with their couplings), then ``local`` again.

Prints, for each, the Krylov iterations, the set-up time (factorisation, coarse matrix) and
the solve time, and the true residual of the result.

    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/contact_preconditioner.py \\
        results/coil/stowed --spacing 2 4 8
"""

import argparse
import time
from pathlib import Path

import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc
from stowed_solver import stowed_solver

from tapecoil.contact.term import SelfContactTerm, add_blocks
from tapecoil.core import compat

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("stowed", type=Path, help="checkpoint directory (a coiling run's stowed/)")
parser.add_argument(
    "--spacing", type=float, nargs="*", default=[2.0, 4.0], help="hat spacing, in node spacings"
)
parser.add_argument("--across", type=int, default=2, help="coarse functions across the width (1: constant)")
parser.add_argument("--repeat", type=int, default=2)
parser.add_argument("--sectors", type=int, nargs="*", default=[], help="angular sectors (one rank)")
parser.add_argument("--overlap", type=float, default=0.25, help="sectors' overlap, a fraction of their width")
parser.add_argument(
    "--smooth", type=int, nargs="*", default=[0, 2], help="Jacobi smoothings of the coarse space"
)
args = parser.parse_args()

comm = MPI.COMM_WORLD
model, solver = stowed_solver(args.stowed, comm, operator=True)
A = solver.A
J = solver._operator
J.assemble() if J is not None else None
terms = [t for t in solver.terms if isinstance(t, SelfContactTerm)]
assert terms, "the checkpoint's run has no contact between turns (contact.turns = 'surface')"
term = terms[0]
contact = term.contact
pairs = term.current()

b = A.createVecLeft()
solver._residual(None, solver.x, b)
if b.norm() < 1e-6 * max(A.norm(), 1.0):
    b.setRandom()
if comm.rank == 0:
    print(f"dofs {A.getSize()[0]}  pairs {comm.allreduce(len(pairs.node))}  |b| {b.norm():.3e}", flush=True)

# the local matrix: the forms' pattern, every pair's blocks but its node-cell couplings
t0 = time.perf_counter()
local = dolfinx.fem.petsc.create_matrix(solver.J_form)
compat.assemble_matrix(local, solver.J_form, solver.bcs)
local.assemble()
matrix, _ = contact.jacobian_blocks(pairs)
blocks = term.weight * matrix.copy()
blocks[:, :3, 3:] = 0.0
blocks[:, 3:, :3] = 0.0
rows = term._pair_rows(pairs)
local.setOption(PETSc.Mat.Option.IGNORE_ZERO_ENTRIES, True)
local.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
# only the entries inside the shell's pattern: a node's own 3 x 3 and its partner cell's 27 x 27
add_blocks(local, rows[:, :3], blocks[:, :3, :3])
add_blocks(local, rows[:, 3:], blocks[:, 3:, 3:])
local.assemble()
t_local = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
nz = lambda M: M.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"]  # noqa: E731
if comm.rank == 0:
    print(
        f"nonzeros: assembled {nz(A):.0f}  local {nz(local):.0f}  (local built in {t_local:.3f} s)",
        flush=True,
    )


def lumped_matrix():
    """The forms' matrix and each pair's blocks with its partner cell's nine nodes collapsed onto
    the one nearest its closest point (a rigid translation kept exactly): each pair couples two
    nodes, not a node and a cell's nine, so the separators through the coil thin."""
    t0 = time.perf_counter()
    M = dolfinx.fem.petsc.create_matrix(solver.J_form)
    compat.assemble_matrix(M, solver.J_form, solver.bcs)
    M.assemble()
    cells = contact.cells[pairs.cell]  # (P, 9)
    nearest = cells[np.arange(len(cells)), np.argmax(pairs.N, axis=1)]
    T = np.zeros((30, 6))
    T[:3, :3] = np.eye(3)
    T[3:, 3:] = np.tile(np.eye(3), (9, 1))
    collapsed = np.einsum("ai,pab,bj->pij", T, term.weight * matrix, T)
    rows = np.concatenate([term.u_rows[pairs.node], term.u_rows[nearest]], axis=1)
    term._widen(M, rows)  # the pairs' node-to-node couplings, preallocated
    add_blocks(M, rows, collapsed)
    M.assemble()
    if comm.rank == 0:
        print(f"nonzeros: lumped {nz(M):.0f}  (built in {time.perf_counter() - t0:.3f} s)", flush=True)
    return M


# on two ranks this tool stopped with a segmentation fault once the lumped matrix was added (not
# traced): one rank only, as the sectors
lumped = lumped_matrix() if comm.size == 1 else None


def lu(M):
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(M)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setUp()
    return ksp


def coarse_space(spacing: float, across: int) -> PETSc.Mat:
    """Z (n x m): the pairs' nodes' normal direction on hat functions along the tape."""
    nodes = np.unique(np.concatenate([pairs.node, contact.cells[pairs.cell].ravel()]))
    nodes = np.unique(np.concatenate(comm.allgather(nodes)))
    s = contact.material[:, 0]
    w = contact.material[:, 1]
    ds = np.median(np.diff(np.unique(np.round(s, 12))))
    H = spacing * ds
    lo, hi = s[nodes].min(), s[nodes].max()
    centres = np.arange(lo, hi + H, H)
    normals = pairs.nodal  # every node's unit normal at this state
    wc = (w - w.mean()) / max(np.ptp(w) / 2, 1e-30)
    start, stop = A.getOwnershipRange()
    u_dofs = contact.surface.u_dofs  # (N, 3) global rows
    m = len(centres) * across
    Z = PETSc.Mat().createAIJ(((stop - start, None), (None, m)), comm=comm)
    Z.setPreallocationNNZ((2 * across * 3, 2 * across * 3))
    Z.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    inside = (s >= lo - H) & (s <= hi + H)
    for node in np.flatnonzero(inside):
        for k in range(3):
            row = u_dofs[node, k]
            if row < start or row >= stop:
                continue
            x = (s[node] - lo) / H
            j0 = int(np.floor(x))
            for j, hat in ((j0, 1 - (x - j0)), (j0 + 1, x - j0)):
                if 0 <= j < len(centres) and hat > 0:
                    for a in range(across):
                        Z.setValue(row, j * across + a, hat * normals[node, k] * wc[node] ** a)
    Z.assemble()
    return Z


def smoothed(Z: PETSc.Mat, steps: int, omega: float = 2.0 / 3.0) -> PETSc.Mat:
    """Z smoothed by Jacobi on the assembled matrix: (I - omega D^-1 A)^steps Z."""
    d = A.getDiagonal()
    d.reciprocal()
    for _ in range(steps):
        AZ = A.matMult(Z)
        AZ.diagonalScale(d, None)
        Z = Z.copy()
        Z.axpy(-omega, AZ, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    return Z


class TwoLevel:
    def __init__(self, A, local_ksp, Z):
        self.A, self.local, self.Z = A, local_ksp, Z
        E = A.PtAP(Z)
        dense = E.convert("dense") if comm.size == 1 else None
        # the coarse matrix, gathered on every rank (it is small)
        m = E.getSize()[0]
        rstart, rend = E.getOwnershipRange()
        mine = np.zeros((m, m))
        for i in range(rstart, rend):
            cols, vals = E.getRow(i)
            mine[i, cols] = vals
        self.E = comm.allreduce(mine)
        self.lu = np.linalg.inv(self.E + 1e-300 * np.eye(m)) if m else None
        self.zr = Z.createVecLeft()
        self.zc = Z.createVecRight()
        self.t1, self.t2 = A.createVecLeft(), A.createVecLeft()
        del dense

    def coarse(self, r, out):
        self.Z.multTranspose(r, self.zc)
        c = np.concatenate(comm.allgather(self.zc.getArray()))
        y = self.lu @ c
        rs, re = self.zc.getOwnershipRange()
        self.zc.setArray(y[rs:re])
        self.Z.mult(self.zc, out)

    def apply(self, pc, x, y):
        self.coarse(x, y)  # y = Q x
        self.A.mult(y, self.t1)
        self.t1.aypx(-1.0, x)  # r - A y
        self.local.solve(self.t1, self.t2)
        y.axpy(1.0, self.t2)
        self.A.mult(y, self.t1)
        self.t1.aypx(-1.0, x)
        self.coarse(self.t1, self.t2)
        y.axpy(1.0, self.t2)


def gmres(pc_setup, label, P=None):
    t0 = time.perf_counter()
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(J if J is not None else A, A if P is None else P)
    ksp.setType("gmres")
    ksp.setPCSide(PETSc.PC.Side.RIGHT)
    ksp.setGMRESRestart(200)
    ksp.setTolerances(rtol=1e-8, max_it=400)
    pc_setup(ksp.getPC())
    ksp.setUp()
    setup = time.perf_counter() - t0
    x = A.createVecRight()
    t0 = time.perf_counter()
    ksp.solve(b, x)
    solve = time.perf_counter() - t0
    r = b.duplicate()
    (J if J is not None else A).mult(x, r)
    r.aypx(-1.0, b)
    setup, solve = (comm.allreduce(v, op=MPI.MAX) for v in (setup, solve))
    if comm.rank == 0:
        print(
            f"{label:28s} its {ksp.getIterationNumber():4d}  reason {ksp.getConvergedReason():3d}"
            f"  set-up {setup:.3f} s  solve {solve:.3f} s  true residual {r.norm() / b.norm():.1e}",
            flush=True,
        )
    return ksp


def lu_pc(pc):
    pc.setType("lu")
    pc.setFactorSolverType("mumps")


for _ in range(args.repeat):
    gmres(lu_pc, "lu (assembled)")
    gmres(lu_pc, "lu (local)", local)
    if lumped is not None:
        gmres(lu_pc, "lu (lumped)", lumped)
for spacing, steps in [(sp, st) for sp in args.spacing for st in args.smooth]:
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        local_ksp = lu(local)
        Z = smoothed(coarse_space(spacing, args.across), steps)
        two = TwoLevel(A, local_ksp, Z)
        t_build = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)

        def shell_pc(pc, two=two):
            pc.setType("python")
            pc.setPythonContext(two)

        if comm.rank == 0:
            print(f"  coarse space {Z.getSize()[1]} functions, built with the local LU in {t_build:.3f} s")
        gmres(shell_pc, f"two-level spacing {spacing:g} smooth {steps}")


class Sectors:
    """local, additive Schwarz on angular sectors of the coil through all its turns, local."""

    def __init__(self, count: int, overlap: float):
        nodes = contact.surface.nodes
        X = nodes.positions(model.model.q.x.array).T
        touching = np.unique(np.concatenate([pairs.node, contact.cells[pairs.cell].ravel()]))
        centre = pairs.positions[touching].mean(axis=0)  # the coil's nodes go round its axis
        angle = np.arctan2(X[:, 2] - centre[2], X[:, 0] - centre[0])
        s = nodes.xi[0]
        coil = (s >= contact.material[touching, 0].min()) & (s <= contact.material[touching, 0].max())
        dofs = np.concatenate([nodes.u_dofs, nodes.theta_dofs], axis=1)
        width = 2 * np.pi / count
        self.sets = []
        for i in range(count):
            start = -np.pi + (i - overlap) * width
            inside = coil & (np.mod(angle - start, 2 * np.pi) <= width * (1 + 2 * overlap))
            index = np.unique(dofs[inside].ravel()).astype(PETSc.IntType)
            self.sets.append(PETSc.IS().createGeneral(index, comm=PETSc.COMM_SELF))
        self.solvers = []
        for M in A.createSubMatrices(self.sets):
            ksp = PETSc.KSP().create(PETSc.COMM_SELF)
            ksp.setOperators(M)
            ksp.setType("preonly")
            ksp.getPC().setType("lu")
            ksp.getPC().setFactorSolverType("mumps")
            ksp.setUp()
            self.solvers.append(ksp)
        self.local = lu(local)
        self.r, self.y = A.createVecLeft(), A.createVecLeft()

    def apply(self, pc, x, y):
        self.local.solve(x, y)
        A.mult(y, self.r)
        self.r.aypx(-1.0, x)
        r = self.r.getArray(readonly=True)
        correction = np.zeros_like(r)
        for index_set, ksp in zip(self.sets, self.solvers, strict=True):
            index = index_set.getIndices()
            rb = PETSc.Vec().createWithArray(r[index].copy(), comm=PETSc.COMM_SELF)
            xb = rb.duplicate()
            ksp.solve(rb, xb)
            correction[index] += xb.getArray()
        y.array[:] += correction
        A.mult(y, self.r)
        self.r.aypx(-1.0, x)
        self.local.solve(self.r, self.y)
        y.axpy(1.0, self.y)


if args.sectors and comm.size > 1:
    raise SystemExit("--sectors: one rank only")
for count in args.sectors:
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        sectors = Sectors(count, args.overlap)
        t_build = time.perf_counter() - t0
        sizes = [index_set.getSize() for index_set in sectors.sets]
        print(
            f"  {count} sectors of {min(sizes)}-{max(sizes)} dofs, factorised with local in {t_build:.3f} s"
        )

        def sector_pc(pc, sectors=sectors):
            pc.setType("python")
            pc.setPythonContext(sectors)

        gmres(sector_pc, f"sectors {count}")
