"""The contact's compiled kernels (``kernels.c``), called with numpy arrays.

Each function here is one loop of ``kernels.c`` over points, cells or pairs; the formulas are
those of :mod:`~tapecoil.contact.projection` and :mod:`~tapecoil.contact.linearisation`. The
library is compiled on first use (:class:`~tapecoil.core.ckernel.CKernel`).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from tapecoil.core.ckernel import CKernel

DECLARATIONS = """
void tc_closest_points(int64_t n, const int64_t* node, const int64_t* cell, const double* x,
                       const int64_t* cells, const double* start, int iterations, const double* nodal,
                       double* ref_out, int8_t* held_out, double* N_out, double* y_out,
                       double* normal_out, double* distance_out, double* direction_out,
                       double* smooth_out, double* along_out, double* beside_out);
void tc_nodal_normals(int64_t n_cells, const int64_t* cells, int64_t n_nodes, const double* x,
                      double* normals, double* length, double* t_out, double* nu_out, double* T_length);
void tc_normal_derivatives(int64_t n_cells, const int64_t* cells, const int64_t* slots, int64_t n_slots,
                           const double* normals, const double* length, const double* t,
                           const double* nu, const double* T_length, double* D);
void tc_pair_blocks(int64_t P, const int64_t* node, const int64_t* cell, const double* x,
                    const int64_t* cells, const double* nodal, const double* ref_in, const int8_t* held_in,
                    const double* side_in, const double* force, const double* stiffness, double* B_out,
                    double* matrix, double* sensitivity);
void tc_apply_normals(int64_t P, const int64_t* cell, const int64_t* cells, const double* N_in,
                      const double* S_in, int64_t n_nodes, const int64_t* slot_start,
                      const int64_t* slot_node, const double* D, int transpose, const double* v,
                      double* work, double* out);
void tc_chain_blocks(int64_t P, const int64_t* nodes, const double* jacobian, const double* M, double* out);
"""


@functools.cache
def library() -> CKernel:
    """The compiled contact kernels (built once per process, kept in the kernel cache)."""
    return CKernel((Path(__file__).with_name("kernels.c")).read_text(), DECLARATIONS, "tapecoil_contact")


def _doubles(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def _indices(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.int64)


class _Arguments:
    """C pointers to numpy arrays, the arrays kept alive as long as this object."""

    def __init__(self, kernel: CKernel):
        self.kernel, self.kept = kernel, []

    def doubles(self, a):
        if a is None:
            return self.kernel.ffi.NULL
        self.kept.append(a)
        return self.kernel.pointer(a, "double *")

    def indices(self, a):
        self.kept.append(a)
        return self.kernel.pointer(a, "int64_t *")

    def bytes(self, a):
        self.kept.append(a)
        return self.kernel.pointer(a, "int8_t *")


def closest_points(
    node: np.ndarray,
    cell: np.ndarray,
    x: np.ndarray,
    cells: np.ndarray,
    start: np.ndarray | None = None,
    iterations: int = 8,
    nodal: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """For each query k, the point of cell ``cell[k]`` closest to node ``node[k]`` (indices into
    the positions ``x`` (N, 3) and the ``cells`` (Nc, 9)); see
    :func:`tapecoil.contact.projection.closest_points` for the method and the outputs. With the
    nodal unit normals ``nodal`` (N, 3): also the smoothed normal at the closest point
    (``smooth``), the distance along it (``along``) and beside it (``beside``)."""
    k = library()
    a = _Arguments(k)
    node, cell = _indices(node), _indices(cell)
    n = len(node)
    out = {
        "ref": np.empty((n, 2)),
        "held": np.empty((n, 2), dtype=np.int8),
        "N": np.empty((n, 9)),
        "y": np.empty((n, 3)),
        "normal": np.empty((n, 3)),
        "distance": np.empty(n),
        "direction": np.empty((n, 3)),
    }
    if nodal is not None:
        out.update(smooth=np.empty((n, 3)), along=np.empty(n), beside=np.empty(n))
    k.lib.tc_closest_points(
        n,
        a.indices(node),
        a.indices(cell),
        a.doubles(_doubles(x)),
        a.indices(_indices(cells)),
        a.doubles(None if start is None else _doubles(start)),
        iterations,
        a.doubles(None if nodal is None else _doubles(nodal)),
        a.doubles(out["ref"]),
        a.bytes(out["held"]),
        *(a.doubles(out[name]) for name in ("N", "y", "normal", "distance", "direction")),
        *(a.doubles(out.get(name)) for name in ("smooth", "along", "beside")),
    )
    out["held"] = out["held"].astype(bool)
    return out


def nodal_normals(cells: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, dict]:
    """The nodes' unit normals (N, 3) and what their derivatives need (see ``kernels.c``)."""
    k = library()
    a = _Arguments(k)
    cells = _indices(cells)
    n_cells, n_nodes = len(cells), len(x)
    data = {
        "normals": np.empty((n_nodes, 3)),
        "length": np.empty(n_nodes),
        "t": np.empty((n_cells, 9, 2, 3)),
        "nu": np.empty((n_cells, 9, 3)),
        "T_length": np.empty((n_cells, 9)),
    }
    k.lib.tc_nodal_normals(
        n_cells,
        a.indices(cells),
        n_nodes,
        a.doubles(_doubles(x)),
        *(a.doubles(data[name]) for name in ("normals", "length", "t", "nu", "T_length")),
    )
    return data["normals"], data


def normal_derivatives(cells: np.ndarray, slots: np.ndarray, n_slots: int, data: dict) -> np.ndarray:
    """dn_k/dX_j (n_slots, 3, 3) in the slots of each node's neighbourhood (``kernels.c``)."""
    k = library()
    a = _Arguments(k)
    D = np.empty((n_slots, 3, 3))
    k.lib.tc_normal_derivatives(
        len(cells),
        a.indices(_indices(cells)),
        a.indices(_indices(slots)),
        n_slots,
        *(a.doubles(data[name]) for name in ("normals", "length", "t", "nu", "T_length")),
        a.doubles(D),
    )
    return D


def pair_blocks(
    node, cell, x, cells, nodal, ref, held, side, force=None, stiffness=None, matrices: bool = False
):
    """The pairs' force directions B (P, 30) and, with ``matrices``, the force's derivative at
    fixed nodal normals (P, 30, 30) and with respect to m = N_b n_b (P, 30, 3), for the pairs'
    ``force`` and ``stiffness`` (``kernels.c``)."""
    k = library()
    a = _Arguments(k)
    P = len(node)
    B = np.empty((P, 30))
    matrix = np.empty((P, 30, 30)) if matrices else None
    sensitivity = np.empty((P, 30, 3)) if matrices else None
    k.lib.tc_pair_blocks(
        P,
        a.indices(_indices(node)),
        a.indices(_indices(cell)),
        a.doubles(_doubles(x)),
        a.indices(_indices(cells)),
        a.doubles(_doubles(nodal)),
        a.doubles(_doubles(ref)),
        a.bytes(np.ascontiguousarray(held, dtype=np.int8)),
        a.doubles(_doubles(side)),
        a.doubles(None if force is None else _doubles(force)),
        a.doubles(None if stiffness is None else _doubles(stiffness)),
        a.doubles(B),
        a.doubles(matrix),
        a.doubles(sensitivity),
    )
    return (B, matrix, sensitivity) if matrices else B


def apply_normals(cell, cells, N, sensitivity, neighbourhood, D, values, transpose: bool) -> np.ndarray:
    """The pairs' dependence on the nodal normals applied to nodal ``values`` (N, 3): (P, 30)
    pair values; or, ``transpose``, its transpose applied to pair values (P, 30): (N, 3) nodal
    values (``kernels.c``). ``neighbourhood``: (slot_start, slot_node)."""
    k = library()
    a = _Arguments(k)
    start, slot_node = neighbourhood
    n_nodes = len(start) - 1
    P = len(cell)
    out = np.empty((n_nodes, 3)) if transpose else np.empty((P, 30))
    k.lib.tc_apply_normals(
        P,
        a.indices(_indices(cell)),
        a.indices(_indices(cells)),
        a.doubles(_doubles(N)),
        a.doubles(_doubles(sensitivity)),
        n_nodes,
        a.indices(_indices(start)),
        a.indices(_indices(slot_node)),
        a.doubles(_doubles(D)),
        int(transpose),
        a.doubles(_doubles(values)),
        a.doubles(np.empty((n_nodes, 3))),
        a.doubles(out),
    )
    return out


def chain_blocks(nodes: np.ndarray, jacobian: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Pair blocks on the positions of each pair's 10 nodes ``nodes`` (P, 10), ``matrix``
    (P, 30, 30), taken to the nodes' displacements and rotations (P, 60, 60), node by node, with
    dx/dtheta = ``jacobian`` (N, 3, 3) (``kernels.c``)."""
    k = library()
    a = _Arguments(k)
    P = len(nodes)
    out = np.empty((P, 60, 60))
    k.lib.tc_chain_blocks(
        P,
        a.indices(_indices(nodes)),
        a.doubles(_doubles(jacobian)),
        a.doubles(_doubles(matrix)),
        a.doubles(out),
    )
    return out
