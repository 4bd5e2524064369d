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
from dataclasses import dataclass

import numpy as np

from .config import Config, MeshConfig

# Facet tags of the strip's edges, and the cell tag of the strip.
STRIP = 1
ROOT, FREE_END, SIDE_NEG, SIDE_POS = 1, 2, 3, 4

# Preset mesh resolutions: (elements across the width, element length along the tape [m]).
# 'default' is about the thesis's 4 mm elements with 9 across (Sec. 3.1).
PRESETS = {"coarse": (4, 0.0125), "default": (9, 0.004), "fine": (18, 0.002)}


@dataclass(frozen=True)
class MeshResolution:
    """Number of elements across the width and along the length, and the length grading."""

    across: int
    along: int
    grading: float = 1.0

    @classmethod
    def from_config(cls, mesh: MeshConfig, length: float) -> MeshResolution:
        across, size = PRESETS[mesh.preset]
        across = mesh.elements_across or across
        size = mesh.element_size or size
        return cls(across=across, along=max(1, round(length / size)), grading=mesh.grading)


class Surface:
    """A shell mid-surface given by an exact map phi0 from a rectangle of parameters.

    The parameter rectangle is [0, length] x [-width/2, width/2] for strips and a geometry's own
    ranges otherwise (``xi_range``). Subclasses give phi0 (numpy and UFL), its Jacobian and how
    gmsh builds the mesh. Edge tags: ROOT at xi_1 = min, FREE_END at xi_1 = max, SIDE_NEG at
    xi_2 = min and SIDE_POS at xi_2 = max.
    """

    xi_range: tuple[tuple[float, float], tuple[float, float]]

    def phi0(self, xi: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def jacobian(self, xi: np.ndarray) -> np.ndarray:
        """d phi0 / d xi at parameter points: shape (3, 2, n)."""
        raise NotImplementedError

    def phi0_ufl(self, xi):
        raise NotImplementedError

    def frame(self, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Orthonormal frame (t1, t2, n0), each (3, n), as the shell module builds it in UFL."""
        J = self.jacobian(xi)
        n0 = np.cross(J[:, 0].T, J[:, 1].T).T
        n0 /= np.linalg.norm(n0, axis=0)
        t1 = J[:, 0] / np.linalg.norm(J[:, 0], axis=0)
        t2 = np.cross(n0.T, t1.T).T
        return t1, t2, n0

    def build_gmsh(self, res: MeshResolution) -> None:
        """Mesh the parameter rectangle in the current gmsh model, nodes in parameter coordinates."""
        _build_parameter_rectangle(self.xi_range, res)


@dataclass(frozen=True)
class StripGeometry(Surface):
    """A cylindrical strip: arc radius R [m] (inf: flat), arc width b [m], length L [m]."""

    R: float
    width: float
    length: float

    @classmethod
    def from_config(cls, config: Config) -> StripGeometry:
        return cls(R=config.tape.R, width=config.tape.b, length=config.tape.L)

    @property
    def xi_range(self):
        return ((0.0, self.length), (-self.width / 2, self.width / 2))

    @property
    def flat(self) -> bool:
        return math.isinf(self.R)

    def phi0(self, xi: np.ndarray) -> np.ndarray:
        """3D mid-surface points (3, n) of parameter points xi (2, n) or (3, n)."""
        x, s = xi[0], xi[1]
        if self.flat:
            return np.vstack([x, s, np.zeros_like(x)])
        return np.vstack([x, self.R * np.sin(s / self.R), self.R * (1 - np.cos(s / self.R))])

    def jacobian(self, xi: np.ndarray) -> np.ndarray:
        n = xi.shape[1]
        J = np.zeros((3, 2, n))
        J[0, 0] = 1.0
        a = np.zeros(n) if self.flat else xi[1] / self.R
        J[1, 1], J[2, 1] = np.cos(a), np.sin(a)
        return J

    def phi0_inverse(self, X: np.ndarray) -> np.ndarray:
        """Parameter points (2, n) of 3D mid-surface points X (3, n); inverse of :meth:`phi0`."""
        if self.flat:
            return np.vstack([X[0], X[1]])
        return np.vstack([X[0], self.R * np.arctan2(X[1], self.R - X[2])])

    def phi0_ufl(self, xi):
        """The map phi0 as a UFL vector of the parameter coordinates (SpatialCoordinate)."""
        import ufl

        if self.flat:
            return ufl.as_vector([xi[0], xi[1], 0.0])
        return ufl.as_vector(
            [xi[0], self.R * ufl.sin(xi[1] / self.R), self.R * (1 - ufl.cos(xi[1] / self.R))]
        )

    def build_gmsh(self, res: MeshResolution) -> None:
        """gmsh builds the 3D strip; its nodes are then moved to parameter coordinates."""
        build_strip_gmsh(self, res)
        _to_parameter_coordinates(self)


@dataclass(frozen=True)
class AnnulusGeometry(Surface):
    """A flat annulus R_inner <= r <= R_outer in the x-y plane, slit along the +x axis.

    Parameters: xi_1 = polar angle (0 to 2 pi, the slit's two edges are ROOT and FREE_END),
    xi_2 = radius (SIDE_NEG inner, SIDE_POS outer edge).
    """

    R_inner: float
    R_outer: float

    @property
    def xi_range(self):
        return ((0.0, 2 * math.pi), (self.R_inner, self.R_outer))

    def phi0(self, xi: np.ndarray) -> np.ndarray:
        a, r = xi[0], xi[1]
        return np.vstack([r * np.cos(a), r * np.sin(a), np.zeros_like(a)])

    def jacobian(self, xi: np.ndarray) -> np.ndarray:
        a, r = xi[0], xi[1]
        J = np.zeros((3, 2, xi.shape[1]))
        J[0, 0], J[1, 0] = -r * np.sin(a), r * np.cos(a)
        J[0, 1], J[1, 1] = np.cos(a), np.sin(a)
        return J

    def phi0_ufl(self, xi):
        import ufl

        return ufl.as_vector([xi[1] * ufl.cos(xi[0]), xi[1] * ufl.sin(xi[0]), 0.0])


def _progression(n: int, grading: float) -> float:
    """gmsh 'Progression' ratio giving a last/first element length ratio of ``grading``."""
    return grading ** (1.0 / (n - 1)) if n > 1 else 1.0


def build_strip_gmsh(geom: StripGeometry, res: MeshResolution) -> None:
    """Build and mesh the 3D strip in the current gmsh model (call on one rank).

    A structured quadrilateral mesh: ``res.across`` elements across, ``res.along`` along
    (element length growing by ``res.grading`` from root to free end). Physical groups: the
    surface (STRIP) and the edges ROOT (x = 0), FREE_END (x = L), SIDE_NEG and SIDE_POS.
    """
    import gmsh

    occ = gmsh.model.occ
    half = geom.width / 2
    if geom.flat:
        p = [occ.addPoint(0, s, 0) for s in (-half, half)]
        section = occ.addLine(p[0], p[1])
    else:
        # arc in the y-z plane, centre (0, 0, R), from xi_2 = -b/2 to +b/2
        ends = geom.phi0(np.array([[0.0, 0.0], [-half, half]]))
        centre = occ.addPoint(0, 0, geom.R)
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
        if abs(cx) < 1e-9 * geom.length:
            edges[ROOT] = tag
        elif abs(cx - geom.length) < 1e-9 * geom.length:
            edges[FREE_END] = tag
        else:
            edges[SIDE_NEG if cy < 0 else SIDE_POS] = tag
    if len(edges) != 4:  # pragma: no cover - geometry construction is deterministic
        raise RuntimeError(f"could not identify the strip's four edges: {edges}")

    _tag_and_mesh(surface, edges, res, x_root=0.0, x_end=geom.length)


def _build_parameter_rectangle(xi_range, res: MeshResolution) -> None:
    """Structured quadrilateral mesh of a parameter rectangle with the four edges tagged."""
    import gmsh

    (x0, x1), (y0, y1) = xi_range
    surface = gmsh.model.occ.addRectangle(x0, y0, 0, x1 - x0, y1 - y0)
    gmsh.model.occ.synchronize()
    edges = {}
    for _, tag in gmsh.model.getBoundary([(2, surface)], oriented=False):
        cx, cy, _ = gmsh.model.occ.getCenterOfMass(1, tag)
        if abs(cx - x0) < 1e-9 * (x1 - x0):
            edges[ROOT] = tag
        elif abs(cx - x1) < 1e-9 * (x1 - x0):
            edges[FREE_END] = tag
        else:
            edges[SIDE_NEG if abs(cy - y0) < abs(cy - y1) else SIDE_POS] = tag
    _tag_and_mesh(surface, edges, res, x_root=x0, x_end=x1)


def _tag_and_mesh(
    surface: int, edges: dict[int, int], res: MeshResolution, x_root: float, x_end: float
) -> None:
    """Physical groups for the surface and its four edges, then the structured quad mesh."""
    import gmsh

    gmsh.model.addPhysicalGroup(2, [surface], tag=STRIP, name="strip")
    for name, tag in (("root", ROOT), ("free_end", FREE_END), ("side_neg", SIDE_NEG), ("side_pos", SIDE_POS)):
        gmsh.model.addPhysicalGroup(1, [edges[tag]], tag=tag, name=name)
    mesh = gmsh.model.mesh
    for tag in (edges[ROOT], edges[FREE_END]):
        mesh.setTransfiniteCurve(tag, res.across + 1)
    ratio = _progression(res.along, res.grading)
    for side in (SIDE_NEG, SIDE_POS):
        # a side edge may run either way: grade it from the root end
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


@dataclass
class StripMesh:
    """The strip's DOLFINx mesh on the parameter domain, its tags, and its 3D geometry."""

    mesh: object  # dolfinx.mesh.Mesh, 2D parameter coordinates
    cell_tags: object
    facet_tags: object
    geometry: Surface
    resolution: MeshResolution


def create_strip_mesh(comm, geom: Surface, res: MeshResolution, rank: int = 0) -> StripMesh:
    """Mesh a surface with gmsh on ``rank`` and distribute it over ``comm`` (collective).

    The DOLFINx mesh lives in parameter coordinates; ``geom.phi0`` maps it to 3D.
    """
    import gmsh

    from .compat import model_to_mesh

    initialized = gmsh.isInitialized()
    if not initialized:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("tapecoil-strip")
        if comm.rank == rank:
            geom.build_gmsh(res)
        mesh, cell_tags, facet_tags = model_to_mesh(gmsh.model, comm, rank, gdim=2)
        gmsh.model.remove()
    finally:
        if not initialized:
            gmsh.finalize()
    mesh.name = "strip"
    return StripMesh(mesh, cell_tags, facet_tags, geom, res)


def build_hub_gmsh(r_hub: float, h: float, width: float, size: float) -> None:
    """Mesh the hub's cylindrical surface (for output only: contact uses the exact cylinder)."""
    import gmsh

    occ = gmsh.model.occ
    axis = hub_axis_point(r_hub, h)
    cyl = occ.addCylinder(axis[0], -0.6 * width, axis[2], 0, 1.2 * width, 0, r_hub)
    occ.synchronize()
    lateral = [
        tag
        for _, tag in gmsh.model.getBoundary([(3, cyl)], oriented=False)
        if abs(occ.getMass(2, tag) - 2 * math.pi * r_hub * 1.2 * width) < 1e-9
    ]
    gmsh.model.addPhysicalGroup(2, lateral, tag=1, name="hub")
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.model.mesh.generate(2)


def hub_axis_point(r_hub: float, h: float) -> np.ndarray:
    """A point of the hub axis (the axis runs along y): (0, 0, -(r_hub + h/2))."""
    return np.array([0.0, 0.0, -(r_hub + h / 2)])
