"""Surfaces stated once by their map: numpy, UFL and the Jacobian follow from it and agree."""

import math

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.geometry.surfaces import AnnulusGeometry, MappedSurface, StripGeometry


def quarter_cylinder(radius=2.0, length=3.0):
    return MappedSurface(
        lambda xi, ops: (radius * ops.cos(xi[1]), xi[0], radius * ops.sin(xi[1])),
        ((0.0, length), (0.0, math.pi / 2)),
    )


@pytest.mark.parametrize(
    "surface", [StripGeometry(0.0151, 0.0356, 0.5), AnnulusGeometry(6.0, 10.0), quarter_cylinder()]
)
def test_the_jacobian_is_the_derivative_of_the_map(surface):
    assert surface.check() < 1e-8


def test_a_mapped_surface_has_the_analytic_jacobian_and_frame():
    surface = quarter_cylinder(radius=2.0)
    xi = np.array([[0.5, 2.0], [0.3, 1.2]])
    J = surface.jacobian(xi)
    a = xi[1]
    assert np.allclose(J[:, 0], [[0, 0], [1, 1], [0, 0]], atol=1e-15)
    assert np.allclose(J[:, 1], np.vstack([-2 * np.sin(a), 0 * a, 2 * np.cos(a)]), atol=1e-15)
    _, _, n0 = surface.frame(xi)
    # the normal of the cylinder x = 2 cos, z = 2 sin, with t1 = +y and t2 along the arc
    assert np.allclose(np.abs(n0), np.abs(np.vstack([np.cos(a), 0 * a, np.sin(a)])), atol=1e-14)


def octant_of_sphere(top: float):
    """An eighth of the unit sphere, xi_1 the longitude (0 to pi/2), xi_2 the latitude (0 to
    ``top``): at top = pi/2 the edge xi2_max is the pole, where the map is singular."""
    return MappedSurface(
        lambda xi, ops: (ops.cos(xi[1]) * ops.cos(xi[0]), ops.cos(xi[1]) * ops.sin(xi[0]), ops.sin(xi[1])),
        ((0.0, math.pi / 2), (0.0, top)),
    )


def test_a_pole_on_the_edge_of_the_parameter_rectangle_is_refused():
    """A sphere's pole on the edge xi2_max: the whole edge maps to one point, the area element
    vanishes there (and only there). Refused, naming the edge; with a hole about the pole (the
    latitude stopping short of it) the same map passes."""
    with pytest.raises(ValueError, match=r"singular \(zero area element.*on the edge xi2_max.*pole"):
        octant_of_sphere(math.pi / 2).check()
    assert octant_of_sphere(0.45 * math.pi).check() < 1e-8


def test_a_singular_corner_is_found():
    """A map singular at one corner only: (x^2, y^2, x y) has the area element
    2 sqrt(y^4 + x^4 + 4 x^2 y^2), zero at (xi_1, xi_2) = (0, 0) alone."""
    corner = MappedSurface(lambda xi, ops: (xi[0] ** 2, xi[1] ** 2, xi[0] * xi[1]), ((0.0, 1.0), (0.0, 1.0)))
    with pytest.raises(ValueError, match=r"at xi = \(0, 0\) \(the corner of xi1_min and xi2_min\)"):
        corner.check()


def test_a_map_that_folds_is_refused():
    folded = MappedSurface(lambda xi, ops: (xi[0], xi[0], 0 * xi[1]), ((0.0, 1.0), (0.0, 1.0)))
    with pytest.raises(ValueError, match="singular"):
        folded.check()


@pytest.mark.parametrize(
    "functions, fails_on",
    [
        (math, "complex parameters"),  # math.sin takes no array: check() fails at once
        (np, "UFL expressions"),  # numpy's serve the arrays and the complex step, not the forms
    ],
)
def test_a_map_written_without_ops_is_refused_with_the_way_out(functions, fails_on):
    """math.sin or numpy.sin in place of ops.sin: a TypeError that says to use ops, where the
    map is first evaluated on what those functions cannot take."""
    import dolfinx
    import ufl

    surface = MappedSurface(
        lambda xi, ops: (2 * functions.cos(xi[1]), xi[0], 2 * functions.sin(xi[1])),
        ((0.0, 3.0), (0.0, math.pi / 2)),
    )
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 1, 1)

    def evaluate():
        surface.check()
        surface.phi0_ufl(ufl.SpatialCoordinate(mesh))

    way_out = r"Write it with the functions of its ops argument \(ops\.sin, ops\.cos"
    with pytest.raises(TypeError, match=rf"cannot be evaluated on {fails_on}.*{way_out}"):
        evaluate()


def test_a_mapped_surface_meshes_and_integrates_to_its_area():
    """The shell on the quarter cylinder: its reference area is pi r L / 2."""
    import dolfinx

    from tapecoil.geometry.meshes import MeshResolution, create_strip_mesh
    from tapecoil.models.shell import NaghdiShell, ShellMaterial

    surface = quarter_cylinder(radius=2.0, length=3.0)
    strip = create_strip_mesh(MPI.COMM_WORLD, surface, MeshResolution(across=6, along=4))
    shell = NaghdiShell(strip, ShellMaterial(1.0, 0.3, 0.01))
    area = dolfinx.fem.assemble_scalar(dolfinx.fem.form(shell.jacobian * shell.dx))
    assert MPI.COMM_WORLD.allreduce(area) == pytest.approx(math.pi * 2.0 * 3.0 / 2, rel=1e-6)
