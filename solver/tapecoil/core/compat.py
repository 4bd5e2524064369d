"""The DOLFINx 0.9 / 0.10 / 0.11 differences tapecoil meets, hidden behind one small API.

Everything else in the package calls these functions instead of the moved or renamed
DOLFINx ones, so that supporting a new release means touching only this module.
"""

from __future__ import annotations

import dolfinx
import dolfinx.fem.petsc
import dolfinx.la
import numpy as np

DOLFINX_VERSION: tuple[int, int] = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])  # type: ignore[assignment]
"""(major, minor) of the DOLFINx in use."""

if DOLFINX_VERSION < (0, 9):  # pragma: no cover - refused before anything runs
    raise ImportError(f"tapecoil needs DOLFINx >= 0.9, found {dolfinx.__version__}")

if DOLFINX_VERSION >= (0, 10):  # pragma: no cover - exercised on conda / Debian sid
    from dolfinx.io import gmsh as _gmshio
else:
    from dolfinx.io import gmshio as _gmshio


def model_to_mesh(model, comm, rank: int, gdim: int):
    """A gmsh model (meshed on ``rank``) as a distributed DOLFINx mesh with its tags.

    Returns ``(mesh, cell_tags, facet_tags)`` on every version: 0.9 returns that tuple, 0.10+
    a ``MeshData`` named tuple (whose missing tags are None in 0.11).
    """
    data = _gmshio.model_to_mesh(model, comm, rank, gdim=gdim)
    if isinstance(data, tuple) and not hasattr(data, "mesh"):
        return data
    return data.mesh, data.cell_tags, data.facet_tags


def interpolation_points(V) -> np.ndarray:
    """Reference interpolation points of a function space's element (method in 0.9, property after)."""
    points = V.element.interpolation_points
    return points() if callable(points) else points


def create_vector(V):
    """A ghosted PETSc vector laid out like the function space V (0.9 takes a form, 0.10+ a space)."""
    if DOLFINX_VERSION >= (0, 10):  # pragma: no cover
        return dolfinx.fem.petsc.create_vector(V)
    return dolfinx.la.create_petsc_vector(V.dofmap.index_map, V.dofmap.index_map_bs)


def assemble_matrix(A, a, bcs, diagonal: float = 1.0):
    """Assemble the bilinear form ``a`` into A with Dirichlet rows set to ``diagonal``.

    Positional on purpose: the keyword is ``diagonal`` in 0.9 and ``diag`` in 0.11.
    """
    return dolfinx.fem.petsc.assemble_matrix(A, a, bcs, diagonal)


def assemble_matrix_local(A, a, bcs) -> None:
    """Add the bilinear form ``a`` into A through A's local numbering, one dof per index, rows
    and columns of Dirichlet dofs left out (their diagonal is :func:`insert_diagonal`'s).

    A may be a local reference to a block of a larger matrix (``getLocalSubMatrix``), as in
    DOLFINx's own block assembly; its Python wrappers for that differ between 0.9 and 0.10+
    and take lists of forms on one mesh, so tapecoil calls the layer beneath them, which is the
    same on 0.9 to 0.11.
    """
    form = a._cpp_object
    constants = dolfinx.cpp.fem.pack_constants(form)
    coefficients = dolfinx.cpp.fem.pack_coefficients(form)
    cpp_bcs = [bc._cpp_object for bc in bcs]
    dolfinx.cpp.fem.petsc.assemble_matrix(A, form, constants, coefficients, cpp_bcs, True)


def insert_diagonal(A, a, bcs, diagonal: float = 1.0) -> None:
    """Set A's diagonal entries on the Dirichlet dofs of ``a``'s (square) form to ``diagonal``,
    through A's local numbering (see :func:`assemble_matrix_local`); A must be flushed after
    adding and before this call."""
    cpp_bcs = [bc._cpp_object for bc in bcs]
    dolfinx.cpp.fem.petsc.insert_diagonal(A, a.function_spaces[0], cpp_bcs, diagonal)


def collapse(space) -> tuple:
    """``space.collapse()`` as ``(collapsed space, map)`` with the map a flat int32 array.

    The map gives, for each dof of the collapsed space (local and ghost, in its order), the dof
    of the parent space. Its type differs by version: 0.9 and 0.10 return a list of ints (one
    per collapsed dof); 0.11 (mixed-topology support, FEniCS/dolfinx#4133) returns a list of
    int32 arrays, one per cell type of the mesh, so ``np.asarray`` of it has shape (1, n) on the
    single-cell-type meshes tapecoil uses, and indexing a dof array with it adds an axis.
    Detected from the returned value, not from the version number.
    """
    collapsed, dofs = space.collapse()
    dofs = np.asarray(dofs, dtype=np.int32)
    if dofs.ndim == 2:  # one map per cell type (0.11)
        if dofs.shape[0] != 1:  # pragma: no cover - tapecoil meshes have one cell type
            raise NotImplementedError(f"collapse of a space on {dofs.shape[0]} cell types")
        dofs = dofs[0]
    return collapsed, dofs


def start_offscreen_rendering() -> None:
    """Let PyVista render off screen when no X display is set (``DISPLAY`` empty).

    Debian trixie (DOLFINx 0.9) has PyVista 0.44 on VTK 9.3, whose render window needs an X
    server: a virtual one (Xvfb) is started for this process and stops with it. (PyVista's own
    ``start_xvfb`` is not used: it starts a server on the fixed display :99 and leaves it
    running, so a later process, or one in another root, can meet a stale or foreign server.)
    Debian sid (DOLFINx 0.11) has
    PyVista 0.49, which no longer has ``start_xvfb`` (deprecated in 0.45, removed in 0.48), on
    VTK 9.6, which picks its render window at run time: there the EGL window is asked for
    directly (through ``VTK_DEFAULT_OPENGL_WINDOW``), which renders without any display and
    spares VTK's failed attempt at X and its warning. A choice already made in
    ``VTK_DEFAULT_OPENGL_WINDOW`` is kept. Detected from the installed PyVista and VTK, not
    from the version numbers.
    """
    import os

    import pyvista

    pyvista.OFF_SCREEN = True
    if os.environ.get("DISPLAY") or os.environ.get("VTK_DEFAULT_OPENGL_WINDOW"):
        return
    if hasattr(pyvista, "start_xvfb"):  # PyVista < 0.48
        os.environ["DISPLAY"] = start_private_xvfb()
        return
    import vtkmodules.vtkRenderingOpenGL2 as gl

    if hasattr(gl, "vtkEGLRenderWindow"):
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"


def start_private_xvfb(screen: str = "1024x768x24", attempts: int = 64, timeout: float = 30.0) -> str:
    """Start a virtual X server that belongs to this process and return its display (":N").

    The server is asked to die with this process (Linux's parent-death signal), so none is
    left running after an exit, a crash or a kill. Display numbers are tried from one derived
    from the process id until a server starts: X refuses a number whose lock file or socket is
    taken, and its sockets are shared by every process on the machine, chroots included. The
    server reports readiness through ``-displayfd``, so no fixed wait is needed.
    """
    import atexit
    import ctypes
    import os
    import select
    import shutil
    import signal
    import subprocess

    if shutil.which("Xvfb") is None:
        raise RuntimeError("off-screen rendering on this PyVista needs Xvfb (Debian package xvfb)")
    libc = ctypes.CDLL(None, use_errno=True)

    def die_with_parent():
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG

    first = 100 + os.getpid() % 800
    for number in range(first, first + attempts):
        read_end, write_end = os.pipe()
        server = subprocess.Popen(
            ["Xvfb", f":{number}", "-screen", "0", screen, "-nolisten", "tcp", "-displayfd", str(write_end)],
            pass_fds=(write_end,),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=die_with_parent,
        )
        os.close(write_end)
        reply = b""
        with os.fdopen(read_end, "rb") as pipe:
            while not reply.endswith(b"\n") and select.select([pipe], [], [], timeout)[0]:
                chunk = os.read(pipe.fileno(), 64)
                if not chunk:  # the server exited: this display is taken
                    break
                reply += chunk
        if reply.strip() == str(number).encode():
            atexit.register(_stop_server, server)
            return f":{number}"
        _stop_server(server)
    raise RuntimeError(
        f"no virtual X server could be started on displays :{first} to :{first + attempts - 1}"
    )


def _stop_server(server) -> None:
    if server.poll() is None:
        server.terminate()
        try:
            server.wait(timeout=10)
        except Exception:  # pragma: no cover - a server that ignores SIGTERM
            server.kill()


def create_mesh(comm, cells, x, element, partitioner=None):
    """``dolfinx.mesh.create_mesh`` by keyword: 0.10 swapped the positions of x and the element."""
    return dolfinx.mesh.create_mesh(comm, cells=cells, x=x, e=element, partitioner=partitioner)
