"""Off-screen pictures of shell states with PyVista (PNG), for reports and README figures.

The picture is built directly from the finite element state: the vertices of the Q2 function
space moved to phi0 + u, coloured by a scalar field. Without a display, rendering goes through
a virtual X server or VTK's EGL window (compat.start_offscreen_rendering).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tapecoil.core import compat
from tapecoil.core.expression import expression_at
from tapecoil.models.shell import NaghdiShell


def _ensure_display() -> None:
    compat.start_offscreen_rendering()


def shell_grid(model: NaghdiShell, scalar=None, name: str = "field"):
    """A PyVista grid of the deformed shell (this rank's part) with an optional UFL scalar."""
    import basix.ufl
    import dolfinx
    import dolfinx.plot
    import pyvista

    mesh = model.mesh
    cell = mesh.basix_cell()
    V3 = dolfinx.fem.functionspace(mesh, basix.ufl.element("Lagrange", cell, model.degree, shape=(3,)))
    points = compat.interpolation_points(V3)
    position = dolfinx.fem.Function(V3)
    position.interpolate(expression_at(model.display_offset, points))
    topology, cell_types, geometry = dolfinx.plot.vtk_mesh(V3)
    grid = pyvista.UnstructuredGrid(topology, cell_types, geometry + position.x.array.reshape(-1, 3))
    if scalar is not None:
        V1 = dolfinx.fem.functionspace(mesh, basix.ufl.element("Lagrange", cell, model.degree))
        f = dolfinx.fem.Function(V1)
        f.interpolate(expression_at(scalar, compat.interpolation_points(V1)))
        grid.point_data[name] = f.x.array.copy()
    return grid


def render_shell(
    model: NaghdiShell,
    path: str | Path,
    scalar=None,
    name: str = "field",
    title: str = "",
    camera=((0.3, -1.0, 0.5),),
    clim=None,
    extra=(),
) -> Path:
    """Render the deformed shell to a PNG (rank 0 gathers nothing: call it in serial runs)."""
    import pyvista

    _ensure_display()
    grid = shell_grid(model, scalar, name)
    plotter = pyvista.Plotter(off_screen=True, window_size=(1200, 700))
    plotter.set_background("white")
    kwargs = {
        "scalars": name,
        "cmap": "viridis",
        "clim": clim,
        "scalar_bar_args": {"title": name, "color": "black"},
    }
    plotter.add_mesh(
        grid, show_edges=False, smooth_shading=True, **(kwargs if scalar is not None else {"color": "silver"})
    )
    for mesh_, style in extra:
        plotter.add_mesh(mesh_, **style)
    if title:
        plotter.add_text(title, font_size=12, color="black")
    plotter.view_vector(np.asarray(camera[0], dtype=float))
    plotter.camera.zoom(1.1)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    plotter.screenshot(str(path))
    plotter.close()
    return path


def render_on_hub(model: NaghdiShell, axis_point, config, path: str | Path, title: str) -> Path:
    """The tape with a short stretch of its hub, coloured by longitudinal curvature x R."""
    import pyvista

    hub = pyvista.Cylinder(
        center=axis_point,
        direction=(0, 1, 0),
        radius=config.hub.radius,
        height=0.2 * config.tape.b,  # a short hub, so that the coil shows
        resolution=120,
    )
    kx, _ = model.curvatures()
    return render_shell(
        model,
        path,
        scalar=-kx * config.tape.R,
        name="kappa_long R",
        title=title,
        camera=((0.4, -1.0, 0.3),),
        clim=(0.0, 1.5),
        extra=[(hub, {"color": "tan", "opacity": 1.0})],
    )


# -- pictures from the gathered snapshots of a run (any number of ranks) --------------------------
def snapshot_grid(cells_file: str | Path, snapshot_file: str | Path, R: float):
    """The surface of a snapshot (see :class:`tapecoil.core.output.ShellWriter`) as a PyVista grid,
    coloured by the longitudinal curvature times R (its ``t`` in ``grid.field_data``)."""
    import pyvista

    cells = np.load(cells_file)
    snap = np.load(snapshot_file)
    grid = pyvista.UnstructuredGrid(cells["cells"], cells["types"], snap["points"].astype(float))
    grid.point_data["kappa_long R"] = -snap["kappa_long"].astype(float) * R
    grid.field_data["t"] = [float(snap["t"])]
    return grid


def _hub(axis_point, radius: float, width: float):
    """The hub, shorter than the tape is wide, so that the coil's spiral edge shows end-on."""
    import pyvista

    return pyvista.Cylinder(
        center=axis_point, direction=(0, 1, 0), radius=radius, height=0.6 * width, resolution=120
    )


def _frame_camera(plotter, bounds, zoom: float = 1.0) -> None:
    """A view along the hub axis, a little from above, framing ``bounds``."""
    xmin, xmax, ymin, ymax, zmin, zmax = bounds
    centre = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2, (zmin + zmax) / 2])
    size = max(xmax - xmin, zmax - zmin, 1e-3)
    plotter.camera.focal_point = centre
    plotter.camera.position = centre + np.array([0.15, -1.0, 0.25]) * 2.2 * size
    plotter.camera.up = (0.0, 0.0, 1.0)
    plotter.camera.zoom(zoom)


def render_snapshots(
    files: list[Path],
    cells_file: Path,
    path: str | Path,
    config,
    axis_point,
    titles: list[str],
    shape: tuple[int, int] | None = None,
    zoom: float = 1.0,
) -> Path:
    """One PNG with a panel per snapshot file, the hub drawn, a common colour scale."""
    import pyvista

    _ensure_display()
    shape = shape or (1, len(files))
    plotter = pyvista.Plotter(off_screen=True, shape=shape, window_size=(600 * shape[1], 450 * shape[0]))
    plotter.set_background("white")
    for i, (f, title) in enumerate(zip(files, titles, strict=True)):
        plotter.subplot(*divmod(i, shape[1]))
        grid = snapshot_grid(cells_file, f, config.tape.R)
        plotter.add_mesh(
            grid,
            scalars="kappa_long R",
            cmap="viridis",
            clim=(0.0, 1.5),
            smooth_shading=True,
            scalar_bar_args={"title": "kappa_long R", "color": "black"},
        )
        plotter.add_mesh(_hub(axis_point, config.hub.radius, config.tape.b), color="tan")
        plotter.add_text(title, font_size=11, color="black")
        _frame_camera(plotter, grid.bounds, zoom)
    path = Path(path)
    plotter.screenshot(str(path))
    plotter.close()
    return path


def animate_snapshots(
    sequences: list[tuple[list[Path], Path, str]], path: str | Path, config, axis_point, fps: int = 8
) -> Path:
    """A GIF of every snapshot in order; ``sequences``: (snapshot files, cells file, label) per
    phase. The view keeps its direction and follows the tape: each frame frames its own
    surface, so the camera closes in on the coil as it is wound and backs away as it deploys."""
    import pyvista

    _ensure_display()
    plotter = pyvista.Plotter(off_screen=True, window_size=(800, 500))
    plotter.set_background("white")
    plotter.open_gif(str(path), fps=fps)
    hub = _hub(axis_point, config.hub.radius, config.tape.b)
    for files, cells_file, label in sequences:
        unit = "rad" if label == "coiling" else "s"
        for f in files:
            grid = snapshot_grid(cells_file, f, config.tape.R)
            plotter.clear()
            plotter.add_mesh(
                grid,
                scalars="kappa_long R",
                cmap="viridis",
                clim=(0.0, 1.5),
                scalar_bar_args={"title": "kappa_long R", "color": "black"},
            )
            plotter.add_mesh(hub, color="tan")
            plotter.add_text(f"{label}: {grid.field_data['t'][0]:.4g} {unit}", font_size=12, color="black")
            _frame_camera(plotter, grid.bounds)
            plotter.write_frame()
    plotter.close()
    return Path(path)
