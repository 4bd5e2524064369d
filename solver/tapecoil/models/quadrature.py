"""The shell's quadrature: the measures of the solve and the PSRI split of its energies.

``technology`` "full" integrates every energy with full quadrature; "psri" splits the membrane
and shear energies into a fraction min(h^2/h_e^2, 1) with full and the rest with reduced
quadrature (the locking measures of :mod:`tapecoil.models.shell`'s docstring), h_e^2 the
element's area measure on the 3D mid-surface at the quadrature point, |det dxi/dX| sqrt(det a0)
(half that on triangles: the unit triangle's area).
"""

from __future__ import annotations

import ufl

TECHNOLOGIES = ("full", "psri")


class ShellQuadrature:
    """The solve's measures on ``strip`` for elements of ``degree`` and how ``technology``
    integrates the energy densities. ``h`` is the thickness [m] and ``area_scale`` the area
    element sqrt(det a0) of the map to 3D (UFL), by which every density is integrated."""

    def __init__(self, strip, degree: int, technology: str, h: float, area_scale):
        mesh = strip.mesh
        self.area_scale = area_scale
        # 'full' integrates the polynomial part exactly on the affine parameter mesh; 'reduced'
        # is one Gauss point fewer per direction
        self.full = 2 * degree + 1
        self.reduced = 2 * degree - 1
        self.dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": self.full})
        self.dx_reduced = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": self.reduced})
        self.ds = ufl.Measure(
            "ds", domain=mesh, subdomain_data=strip.facet_tags, metadata={"quadrature_degree": self.full}
        )
        if technology == "full":
            self.alpha = None
        else:
            # physical element size: reference cell [0, 1]^2 (or the unit triangle) times the
            # area scale sqrt(det a0) of the map to 3D
            area = abs(ufl.JacobianDeterminant(mesh)) * area_scale
            if mesh.topology.cell_name() != "quadrilateral":
                area = area / 2
            self.alpha = ufl.min_value(h**2 / area, 1.0)

    def integrate(self, membrane, bending, shear):
        """Membrane, bending and shear densities as forms with the solve's quadrature (PSRI split)."""
        dA = self.area_scale
        if self.alpha is None:
            return membrane * dA * self.dx, bending * dA * self.dx, shear * dA * self.dx
        a = self.alpha

        def split(density):
            return a * density * dA * self.dx + (1 - a) * density * dA * self.dx_reduced

        return split(membrane), bending * dA * self.dx, split(shear)
