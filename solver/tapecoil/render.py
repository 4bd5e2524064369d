"""Off-screen pictures of shell states with PyVista (PNG), for reports and README figures.

The picture is built directly from the finite element state: the vertices of the Q2 function
space moved to phi0 + u, coloured by a scalar field. Rendering needs an X server: a virtual
one (Xvfb) is started when no display is set.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from . import compat
from .shell import NaghdiShell


def _ensure_display() -> None:
    import pyvista

    pyvista.OFF_SCREEN = True
    if not os.environ.get("DISPLAY"):
        pyvista.start_xvfb()


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
    position.interpolate(dolfinx.fem.Expression(model.display_offset, points))
    topology, cell_types, geometry = dolfinx.plot.vtk_mesh(V3)
    grid = pyvista.UnstructuredGrid(topology, cell_types, geometry + position.x.array.reshape(-1, 3))
    if scalar is not None:
        V1 = dolfinx.fem.functionspace(mesh, basix.ufl.element("Lagrange", cell, model.degree))
        f = dolfinx.fem.Function(V1)
        f.interpolate(dolfinx.fem.Expression(scalar, compat.interpolation_points(V1)))
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
