"""Geometry of the tape and the hub, meshed with gmsh.

Coordinates. The tape runs along +x from its root at x = 0 to its free end at x = L; its width
runs along y. The cross-section is a circular arc of radius R and angle alpha whose centre lies
on the +z side, so the edges stand higher than the centre line (z = 0). The hub is a rigid
cylinder of radius r_hub with its axis along y, below the tape and tangent to its root: its
surface touches the tape's inner face (z = -h/2) at x = 0, so the axis passes through
(0, y, -(r_hub + h/2)). Coiling the tape onto it bends the tape towards -z, opposite in sense to
the transverse curvature, so the section flattens onto the hub (opposite-sense coiling).

The shell is formulated on a flat parameter domain: xi_1 = x along the tape, xi_2 = arc length
across it (-b/2 <= xi_2 <= b/2, b = R alpha). The exact map

    phi0(xi) = (xi_1, R sin(xi_2 / R), R (1 - cos(xi_2 / R)))

takes it to the 3D mid-surface. gmsh builds that 3D surface (the arc extruded along x) and its
structured mesh; the nodes are then taken to parameter coordinates with the exact inverse map
before the mesh is handed to DOLFINx, so the parameter mesh and the 3D surface used for output
are one and the same surface.
"""

from __future__ import annotations

import math
import numbers
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tapecoil.config import MeshConfig
from tapecoil.core.collective import raise_everywhere
from tapecoil.geometry.surfaces import StripGeometry, Surface

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10 (conda environments)
    import tomli as tomllib

# Facet tags of a surface's edges, named by the parameter bound each lies on, and the cell tag.
STRIP = 1
XI1_MIN, XI1_MAX, XI2_MIN, XI2_MAX = 1, 2, 3, 4
# the same edges as a tape's: its root, its free end and its two long sides
ROOT, FREE_END, SIDE_NEG, SIDE_POS = XI1_MIN, XI1_MAX, XI2_MIN, XI2_MAX
# The names of the physical groups in gmsh's model (and its .msh files): a general surface's
# edges by the parameter bound they lie on, a tape's strip by what they are on the tape. The
# tags are the same; only the names differ.
EDGE_NAMES = {XI1_MIN: "xi1_min", XI1_MAX: "xi1_max", XI2_MIN: "xi2_min", XI2_MAX: "xi2_max"}
TAPE_EDGE_NAMES = {ROOT: "root", FREE_END: "free_end", SIDE_NEG: "side_neg", SIDE_POS: "side_pos"}

# The preset mesh resolutions are kept in meshes/presets.toml at the top of the project, where
# they are read and changed; this package reaches it through the link presets.toml beside this
# module (installed as package data, a copy of the file).
PRESETS_FILE = Path(__file__).with_name("presets.toml")


def load_presets(path: str | Path = PRESETS_FILE) -> dict[str, tuple[int, float]]:
    """Mesh presets: name -> (elements across the width, element length along the tape [m])."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise RuntimeError(f"cannot read the mesh presets {path}: {exc}") from None
    presets = {}
    for name, table in data.items():
        ok = isinstance(table, dict) and set(table) == {"elements_across", "element_size"}
        if ok:  # type() rather than isinstance(): TOML's true is no element count
            across, size = table["elements_across"], table["element_size"]
            ok = type(across) is int and across > 0 and type(size) in (int, float) and size > 0
        if not ok:
            raise RuntimeError(
                f"{path}: [{name}] must hold exactly elements_across (an integer > 0) and "
                f"element_size (a length > 0 [m]); got {table!r}"
            )
        presets[name] = (across, float(size))
    return presets


PRESETS = load_presets()


@dataclass(frozen=True)
class MeshResolution:
    """The structured mesh of a parameter rectangle: how many elements in each direction.

    ``across``: elements along the second parameter xi_2, i.e. on each of the edges xi1_min and
    xi1_max; on a tape, across its width (from side to side). ``along``: elements along the
    first parameter xi_1, i.e. on each of the edges xi2_min and xi2_max; on a tape, along its
    length (from the root to the free end). ``grading``: the last element along xi_1 over the
    first (1: all the same length; above 1 they grow towards xi1_max, the free end). A general
    surface is meshed the same way: e.g. on the slit annulus (xi_1 the polar angle, xi_2 the
    radius) ``along`` elements go round it and ``across`` elements span the radius.
    """

    across: int
    along: int
    grading: float = 1.0

    def __post_init__(self):
        for name, what in (
            ("across", "elements along xi_2, across a tape's width"),
            ("along", "elements along xi_1, along a tape's length"),
        ):
            value = getattr(self, name)
            if not isinstance(value, numbers.Integral) or isinstance(value, bool) or value < 1:
                raise ValueError(f"MeshResolution: {name} = {value!r} must be a positive integer ({what})")
        grading = self.grading
        if isinstance(grading, bool) or not isinstance(grading, numbers.Real) or not 0 < grading < math.inf:
            raise ValueError(
                f"MeshResolution: grading = {grading!r} must be a positive number (the last element "
                "along xi_1 over the first)"
            )

    @classmethod
    def from_config(cls, mesh: MeshConfig, length: float) -> MeshResolution:
        across, size = PRESETS[mesh.preset]
        across = mesh.elements_across or across
        size = mesh.element_size or size
        return cls(across=across, along=max(1, round(length / size)), grading=mesh.grading)

    def element_lengths(self, length: float) -> tuple[float, float]:
        """Lengths [m] of the first (root) and last (free end) elements along a strip of ``length``."""
        ratio = _progression(self.along, self.grading)
        first = length / self.along if ratio == 1.0 else length * (ratio - 1) / (ratio**self.along - 1)
        return first, first * ratio ** (self.along - 1)


def _progression(n: int, grading: float) -> float:
    """gmsh 'Progression' ratio giving a last/first element length ratio of ``grading``."""
    return grading ** (1.0 / (n - 1)) if n > 1 else 1.0


def build_strip_gmsh(geom: StripGeometry, res: MeshResolution) -> None:
    """Build and mesh the 3D strip in the current gmsh model (call on one rank).

    A structured quadrilateral mesh: ``res.across`` elements across, ``res.along`` along
    (element length growing by ``res.grading`` from root to free end). Physical groups: the
    surface ("strip", tag STRIP) and the edges "root" (ROOT, x = start), "free_end" (FREE_END,
    x = start + L), "side_neg" and "side_pos" (SIDE_NEG and SIDE_POS, the sides at y < 0 and y > 0).
    """
    import gmsh

    occ = gmsh.model.occ
    half = geom.width / 2
    x0 = geom.start
    if geom.flat:
        p = [occ.addPoint(x0, s, 0) for s in (-half, half)]
        section = occ.addLine(p[0], p[1])
    else:
        # arc in the y-z plane, centre (0, 0, R), from xi_2 = -b/2 to +b/2
        ends = geom.phi0(np.array([[x0, x0], [-half, half]]))
        centre = occ.addPoint(x0, 0, geom.R)
        p = [occ.addPoint(*ends[:, i]) for i in range(2)]
        section = occ.addCircleArc(p[0], centre, p[1])
        occ.remove([(0, centre)])
    out = occ.extrude([(1, section)], geom.length, 0, 0)
    occ.synchronize()
    surface = next(tag for dim, tag in out if dim == 2)

    # classify the four edges of the surface by where their centres lie
    edges = {}
    for _, tag in gmsh.model.getBoundary([(2, surface)], oriented=False):
        cx, cy, _cz = occ.getCenterOfMass(1, tag)
        if abs(cx - x0) < 1e-9 * geom.length:
            edges[ROOT] = tag
        elif abs(cx - x0 - geom.length) < 1e-9 * geom.length:
            edges[FREE_END] = tag
        else:
            edges[SIDE_NEG if cy < 0 else SIDE_POS] = tag
    if len(edges) != 4:  # pragma: no cover - geometry construction is deterministic
        raise RuntimeError(f"could not identify the strip's four edges: {edges}")

    _tag_and_mesh(surface, edges, res, x_root=x0, x_end=x0 + geom.length, names=("strip", TAPE_EDGE_NAMES))


def _build_parameter_rectangle(xi_range, res: MeshResolution) -> None:
    """Structured quadrilateral mesh of a parameter rectangle with the four edges tagged.

    Physical groups: the surface ("surface", tag STRIP) and its edges by the parameter bound each
    lies on, "xi1_min", "xi1_max", "xi2_min" and "xi2_max" (tags XI1_MIN ... XI2_MAX), the names
    :class:`~tapecoil.models.problem.ShellProblem` gives them.
    """
    import gmsh

    (x0, x1), (y0, y1) = xi_range
    surface = gmsh.model.occ.addRectangle(x0, y0, 0, x1 - x0, y1 - y0)
    gmsh.model.occ.synchronize()
    edges = {}
    for _, tag in gmsh.model.getBoundary([(2, surface)], oriented=False):
        cx, cy, _ = gmsh.model.occ.getCenterOfMass(1, tag)
        if abs(cx - x0) < 1e-9 * (x1 - x0):
            edges[XI1_MIN] = tag
        elif abs(cx - x1) < 1e-9 * (x1 - x0):
            edges[XI1_MAX] = tag
        else:
            edges[XI2_MIN if abs(cy - y0) < abs(cy - y1) else XI2_MAX] = tag
    _tag_and_mesh(surface, edges, res, x_root=x0, x_end=x1, names=("surface", EDGE_NAMES))


def _tag_and_mesh(
    surface: int,
    edges: dict[int, int],
    res: MeshResolution,
    x_root: float,
    x_end: float,
    names: tuple[str, dict[int, str]],
) -> None:
    """Physical groups for the surface and its four edges, then the structured quad mesh.

    ``edges``: edge tag (XI1_MIN ...) -> gmsh curve; ``names``: the surface's group name and
    each edge tag's name.
    """
    import gmsh

    surface_name, edge_names = names
    gmsh.model.addPhysicalGroup(2, [surface], tag=STRIP, name=surface_name)
    for tag in (XI1_MIN, XI1_MAX, XI2_MIN, XI2_MAX):
        gmsh.model.addPhysicalGroup(1, [edges[tag]], tag=tag, name=edge_names[tag])
    mesh = gmsh.model.mesh
    # the edges xi_1 = const carry the elements across (along xi_2), the others those along xi_1
    for tag in (edges[XI1_MIN], edges[XI1_MAX]):
        mesh.setTransfiniteCurve(tag, res.across + 1)
    ratio = _progression(res.along, res.grading)
    for side in (XI2_MIN, XI2_MAX):
        # an edge along xi_1 may run either way: grade it from the xi1_min end (a tape's root)
        tag = edges[side]
        start = gmsh.model.getBoundary([(1, tag)], oriented=True)[0][1]
        x_start = gmsh.model.getValue(0, start, [])[0]
        from_root = abs(x_start - x_root) < abs(x_start - x_end)
        mesh.setTransfiniteCurve(tag, res.along + 1, "Progression", ratio if from_root else 1 / ratio)
    mesh.setTransfiniteSurface(surface)
    mesh.setRecombine(2, surface)
    mesh.generate(2)


def _to_parameter_coordinates(geom: StripGeometry) -> None:
    """Move every node of the current gmsh mesh to its parameter coordinates (xi_1, xi_2, 0)."""
    import gmsh

    tags, coords, _ = gmsh.model.mesh.getNodes()
    xi = geom.phi0_inverse(coords.reshape(-1, 3).T)
    for tag, a, b in zip(tags, xi[0], xi[1], strict=True):
        gmsh.model.mesh.setNode(int(tag), [float(a), float(b), 0.0], [])


def build_gmsh(geom: Surface, res: MeshResolution) -> None:
    """Mesh ``geom`` in the current gmsh model, its nodes in parameter coordinates (call on one rank).

    A strip is built in 3D by gmsh (the arc extruded) and its nodes moved to parameter
    coordinates; any other surface is meshed on its parameter rectangle.
    """
    if isinstance(geom, StripGeometry):
        build_strip_gmsh(geom, res)
        _to_parameter_coordinates(geom)
    else:
        _build_parameter_rectangle(geom.xi_range, res)


@dataclass
class StripMesh:
    """The strip's DOLFINx mesh on the parameter domain, its tags, and its 3D geometry."""

    mesh: object  # dolfinx.mesh.Mesh, 2D parameter coordinates
    cell_tags: object
    facet_tags: object
    geometry: Surface
    resolution: MeshResolution


@contextmanager
def _gmsh_model(comm, geom: Surface, res: MeshResolution, rank: int, msh: str | Path | None = None):
    """gmsh's model of ``geom``, meshed on ``rank`` (and written to ``msh``), removed on leaving.

    A failure on ``rank`` (gmsh, or a file it cannot write) is raised on every rank before any
    of them goes on to distribute the mesh, where the others would wait for it for ever.
    """
    import gmsh

    initialized = gmsh.isInitialized()
    if not initialized:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("tapecoil-strip")
        try:
            error = None
            if comm.rank == rank:
                try:
                    build_gmsh(geom, res)
                    if msh is not None:
                        gmsh.write(str(msh))
                except Exception as exc:
                    error = exc
            raise_everywhere(comm, error, rank)
            yield gmsh.model
        finally:
            gmsh.model.remove()
    finally:
        if not initialized:
            gmsh.finalize()


def create_strip_mesh(
    comm, geom: Surface, res: MeshResolution, rank: int = 0, msh: str | Path | None = None
) -> StripMesh:
    """Mesh a surface with gmsh on ``rank`` and distribute it over ``comm`` (collective).

    The DOLFINx mesh lives in parameter coordinates; ``geom.phi0`` maps it to 3D. ``msh``: also
    write gmsh's model there (its nodes in parameter coordinates, the physical groups as tags).
    """
    from tapecoil.core.compat import model_to_mesh

    with _gmsh_model(comm, geom, res, rank, msh) as model:
        mesh, cell_tags, facet_tags = model_to_mesh(model, comm, rank, gdim=2)
    mesh.name = "strip"
    return StripMesh(mesh, cell_tags, facet_tags, geom, res)


@dataclass
class MeshFiles:
    """What :func:`write_strip_mesh` wrote, and the size of the mesh."""

    msh: Path  # gmsh, nodes in parameter coordinates (the solver's mesh)
    xdmf: Path  # DOLFINx: that mesh, 'strip', with its tags 'facets' and 'cells'
    surface_msh: Path  # gmsh, the same cells with their nodes on the 3D mid-surface
    surface_xdmf: Path  # DOLFINx: the 3D mesh, 'surface', with its tags 'facets' and 'cells'
    nodes: int
    cells: int


def write_strip_mesh(
    comm, geom: Surface, res: MeshResolution, directory: str | Path, name: str, rank: int = 0
) -> MeshFiles:
    """Write the mesh the solver builds for ``geom`` at ``res`` into ``directory`` (collective).

    ``<name>.msh`` (gmsh 4.1, nodes in parameter coordinates as the solver uses them) and
    ``<name>.xdmf`` (the DOLFINx mesh on the parameter domain with its facet and cell tags); then
    ``<name>-surface.msh`` and ``<name>-surface.xdmf``, the same cells with their nodes mapped by
    phi0 to the 3D mid-surface, to look at. ``directory`` must exist.
    """
    import dolfinx.io
    import gmsh

    from tapecoil.core.compat import model_to_mesh

    directory = Path(directory)
    msh, xdmf, surface_msh, surface_xdmf = (
        directory / f"{name}{end}" for end in (".msh", ".xdmf", "-surface.msh", "-surface.xdmf")
    )
    with _gmsh_model(comm, geom, res, rank, msh) as model:
        strip = model_to_mesh(model, comm, rank, gdim=2)
        error = None
        if comm.rank == rank:
            try:
                _to_surface_coordinates(geom)
                gmsh.write(str(surface_msh))
            except Exception as exc:
                error = exc
        raise_everywhere(comm, error, rank)
        surface = model_to_mesh(model, comm, rank, gdim=3)
    for path, grid, (mesh, cell_tags, facet_tags) in (
        (xdmf, "strip", strip),
        (surface_xdmf, "surface", surface),
    ):
        mesh.name, facet_tags.name, cell_tags.name = grid, "facets", "cells"
        mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
        with dolfinx.io.XDMFFile(comm, str(path), "w") as f:
            f.write_mesh(mesh)
            for tags in (facet_tags, cell_tags):
                f.write_meshtags(tags, mesh.geometry, f"/Xdmf/Domain/Grid[@Name='{grid}']/Geometry")
    mesh = strip[0]
    return MeshFiles(
        msh,
        xdmf,
        surface_msh,
        surface_xdmf,
        nodes=mesh.geometry.index_map().size_global,
        cells=mesh.topology.index_map(mesh.topology.dim).size_global,
    )


def _to_surface_coordinates(geom: Surface) -> None:
    """Move every node of the current gmsh mesh from parameter coordinates to phi0 (3D)."""
    import gmsh

    tags, coords, _ = gmsh.model.mesh.getNodes()
    X = geom.phi0(coords.reshape(-1, 3).T)
    for tag, point in zip(tags, X.T, strict=True):
        gmsh.model.mesh.setNode(int(tag), [float(c) for c in point], [])
