"""Off-screen pictures of shell states with PyVista (PNG), for reports and README figures.

The picture is built directly from the finite element state: the vertices of the Q2 function
space moved to phi0 + u, coloured by a scalar field. Without a display, rendering goes through
a virtual X server or VTK's EGL window (compat.start_offscreen_rendering).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
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
        center=axis_point, direction=(0, 1, 0), radius=radius, height=_hub_height(width), resolution=120
    )


def _hub_height(width: float) -> float:
    return 0.6 * width


# The direction the camera looks from: along the hub's axis (-y), a little from the free end's
# side and from above, so that the coil's spiral edge and the tape's section both show.
VIEW_DIRECTION = (0.15, -1.0, 0.25)
VIEW_ANGLE = 30.0  # [degree], VTK's default
# Below this ratio of the hub's diameter to the framed extent, the coil is too small to read in
# the whole view and a second panel zooms on the hub region.
SMALL_HUB = 0.15
# The hub region's zoom frames this many hub radii about the axis: the coil (a few thicknesses
# over the hub) and the start of the free part.
HUB_REGION = 3.0
# pixels of a panel of a sequence's picture, and of the animation's frame (width, height)
PANEL = (600, 450)
FRAME = (800, 500)


@dataclass(frozen=True)
class View:
    """A fixed camera framing the box ``bounds`` (xmin, xmax, ymin, ymax, zmin, zmax) [m],
    looking at its centre from :data:`VIEW_DIRECTION`, z up, with a 30 degree view angle."""

    bounds: tuple[float, float, float, float, float, float]

    def camera(self, aspect: float) -> tuple[tuple, tuple, tuple]:
        """Position, focal point and up of the camera in a panel ``aspect`` (width / height)
        wide: far enough back for the box's x-z extent to fit, with a margin, and the box
        raised into the panel's upper part, clear of the colour bar along its foot."""
        xmin, xmax, ymin, ymax, zmin, zmax = self.bounds
        centre = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2, (zmin + zmax) / 2])
        height = max(zmax - zmin, (xmax - xmin) / aspect, 1e-3)
        visible = 1.35 * height
        focal = centre - np.array([0.0, 0.0, 0.12 * visible])
        direction = np.array(VIEW_DIRECTION) / np.linalg.norm(VIEW_DIRECTION)
        distance = visible / 2 / math.tan(math.radians(VIEW_ANGLE / 2))
        position = focal + direction * distance
        return tuple(map(float, position)), tuple(map(float, focal)), (0.0, 0.0, 1.0)

    def apply(self, plotter, aspect: float) -> None:
        """Set the current renderer's camera to this view."""
        position, focal_point, up = self.camera(aspect)
        camera = plotter.camera
        camera.position = position
        camera.focal_point = focal_point
        camera.up = up
        camera.view_angle = VIEW_ANGLE


@dataclass(frozen=True)
class PhaseViews:
    """The views of every frame of a phase: the whole motion, and a zoom on the hub region when
    the hub is small in it (None otherwise)."""

    whole: View
    hub: View | None = None


def union_bounds(bounds: list) -> tuple[float, ...]:
    """The box (xmin, xmax, ymin, ymax, zmin, zmax) that holds every box of ``bounds``."""
    b = np.asarray(bounds, dtype=float).reshape(-1, 6)
    return (b[:, 0].min(), b[:, 1].max(), b[:, 2].min(), b[:, 3].max(), b[:, 4].min(), b[:, 5].max())


def phase_views(frame_bounds: list, axis_point, hub_radius: float, width: float, zoom=None) -> PhaseViews:
    """One camera for all the frames of a phase, so that only the motion changes between them.

    The whole view frames the union of the frames' boxes ``frame_bounds`` and the hub's (its axis
    through ``axis_point`` along y, ``hub_radius``, drawn ``width``-scaled long); the hub stays
    where it is on the picture and the scale is the same in every frame. ``zoom``: also a view
    of the hub region (True), none (False), or one when the hub's diameter is under
    :data:`SMALL_HUB` of the framed extent (None), as on a long tape deployed.
    """
    a = np.asarray(axis_point, dtype=float)
    half = _hub_height(width) / 2
    hub_box = (
        a[0] - hub_radius,
        a[0] + hub_radius,
        a[1] - half,
        a[1] + half,
        a[2] - hub_radius,
        a[2] + hub_radius,
    )
    box = tuple(map(float, union_bounds([*frame_bounds, hub_box])))
    if zoom is None:
        zoom = 2 * hub_radius < SMALL_HUB * max(box[1] - box[0], box[5] - box[4])
    hub = None
    if zoom:
        r = HUB_REGION * hub_radius
        hub = View((a[0] - r, a[0] + r, box[2], box[3], a[2] - r, a[2] + r))
    return PhaseViews(View(box), hub)


def _camera_of(plotter) -> tuple:
    """What the current renderer's camera is: position, focal point, up and view angle."""
    camera = plotter.camera
    return (tuple(camera.position), tuple(camera.focal_point), tuple(camera.up), camera.view_angle)


def _add_tape(plotter, grid, hub, title: str, shading: bool) -> None:
    plotter.add_mesh(
        grid,
        scalars="kappa_long R",
        cmap="viridis",
        clim=(0.0, 1.5),
        smooth_shading=shading,
        scalar_bar_args={"title": "kappa_long R", "color": "black"},
    )
    plotter.add_mesh(hub, color="tan")
    plotter.add_text(title, font_size=11, color="black")


def _snapshot_bounds(files: list[Path], cells_file: Path, R: float) -> list:
    return [snapshot_grid(cells_file, f, R).bounds for f in files]


def render_snapshots(
    files: list[Path],
    cells_file: Path,
    path: str | Path,
    config,
    axis_point,
    titles: list[str],
    shape: tuple[int, int] | None = None,
    views: PhaseViews | None = None,
    cameras: list | None = None,
) -> Path:
    """One PNG with a panel per snapshot file, the hub drawn, a common colour scale and one
    camera for every panel (:func:`phase_views` of the snapshots, unless ``views`` is given).

    With a zoom on the hub region, each snapshot's panel has the zoom beside it. ``cameras``:
    a list to which each panel's camera is appended as rendered (position, focal point, up,
    view angle), the zoom's after its snapshot's.
    """
    import pyvista

    _ensure_display()
    shape = shape or (1, len(files))
    if views is None:
        views = phase_views(
            _snapshot_bounds(files, cells_file, config.tape.R), axis_point, config.hub.radius, config.tape.b
        )
    panels = 2 if views.hub is not None else 1
    rows, cols = shape[0], shape[1] * panels
    plotter = pyvista.Plotter(
        off_screen=True, shape=(rows, cols), window_size=(PANEL[0] * cols, PANEL[1] * rows)
    )
    plotter.set_background("white")
    hub = _hub(axis_point, config.hub.radius, config.tape.b)
    for i, (f, title) in enumerate(zip(files, titles, strict=True)):
        row, col = divmod(i, shape[1])
        grid = snapshot_grid(cells_file, f, config.tape.R)
        for k, (view, label) in enumerate(((views.whole, title), (views.hub, "hub region"))[:panels]):
            plotter.subplot(row, col * panels + k)
            _add_tape(plotter, grid, hub, label, shading=True)
            view.apply(plotter, PANEL[0] / PANEL[1])
    path = Path(path)
    plotter.screenshot(str(path))
    if cameras is not None:
        for i in range(len(files)):
            row, col = divmod(i, shape[1])
            for k in range(panels):
                plotter.subplot(row, col * panels + k)
                cameras.append(_camera_of(plotter))
    plotter.close()
    return path


def animate_snapshots(
    sequences: list[tuple[list[Path], Path, str]],
    path: str | Path,
    config,
    axis_point,
    fps: int = 8,
    views: list[PhaseViews] | None = None,
    cameras: list | None = None,
) -> Path:
    """A GIF of every snapshot in order; ``sequences``: (snapshot files, cells file, label) per
    phase. Each phase keeps one camera (``views``, one per phase; by default :func:`phase_views`
    of all its snapshots), so the hub stays put and the scale holds while the tape moves; where
    the hub is small in that view, a second panel beside it zooms on the hub region.
    ``cameras``: a list to which each frame's (label, camera of each panel as rendered) is
    appended."""
    import pyvista

    _ensure_display()
    R = config.tape.R
    if views is None:
        views = [
            phase_views(_snapshot_bounds(files, cells, R), axis_point, config.hub.radius, config.tape.b)
            for files, cells, _ in sequences
        ]
    panels = 2 if any(v.hub is not None for v in views) else 1
    plotter = pyvista.Plotter(off_screen=True, shape=(1, panels), window_size=(FRAME[0] * panels, FRAME[1]))
    plotter.set_background("white")
    plotter.open_gif(str(path), fps=fps)
    hub = _hub(axis_point, config.hub.radius, config.tape.b)
    for (files, cells_file, label), view in zip(sequences, views, strict=True):
        unit = "rad" if label == "coiling" else "s"
        # a phase whose hub is large enough in its own view still fills the second panel
        hub_view = view.hub or view.whole
        for f in files:
            grid = snapshot_grid(cells_file, f, R)
            title = f"{label}: {grid.field_data['t'][0]:.4g} {unit}"
            plotter.clear()  # every panel's actors
            used = []
            for k, (v, text) in enumerate(((view.whole, title), (hub_view, "hub region"))[:panels]):
                plotter.subplot(0, k)
                _add_tape(plotter, grid, hub, text, shading=False)
                v.apply(plotter, FRAME[0] / FRAME[1])
                used.append(_camera_of(plotter))
            plotter.write_frame()
            if cameras is not None:
                cameras.append((label, used))
    plotter.close()
    return Path(path)
