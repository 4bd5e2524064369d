"""Nonlinear Naghdi (Reissner-Mindlin) shell on a flat parameter domain mapped to 3D.

Kinematics. The reference mid-surface is phi0(xi) (geometry module) with covariant basis
J0 = grad phi0, metric a0 = J0^T J0 and unit normal n0. In an orthonormal director frame
(e1, e2, e3) the director is

    d = Lambda(theta_ref + theta)
      = cos(t0) sin(t1) e1 - sin(t0) e2 + cos(t0) cos(t1) e3,   (t0, t1) = theta_ref + theta,

a rotation by t1 about e2 after a rotation by t0 about e1; theta_ref are the angles of n0, so
theta = 0 is the reference state. The map is singular only where d = +-e2. Two frames:
  - "global" (for tapes): e1, e2, e3 = x, y, z, with y the tape's width axis. theta_1 is the
    rotation about the width axis, so coiling through many turns and folding are unbounded,
    regular theta_1; the director never turns onto the width axis (it leans towards it by at
    most alpha/2 on the curved section).
  - "local" (the default, for general shells): e1 = t1 along the first parameter direction,
    e3 = n0, e2 = n0 x t1, theta_ref = 0. A curved tape section turned by about pi about the
    width axis meets this frame's singularity (the director at 45 degrees on the section
    turns onto t2), which is why tapes use "global".

Strains (covariant, with phi = phi0 + u, F = grad phi):
    membrane  e = (F^T F - a0) / 2
    bending   k = sym(F^T grad d) - sym(J0^T grad n0)
    shear     g = F^T d            (J0^T n0 = 0)
Isotropic plane-stress resultants use the contravariant metric A = a0^-1; the energy per unit
reference area is h/2 C(e):e + h^3/24 C(k):k + kappa G h / 2 g.A.g with
C(S) = E/(1-nu^2) ((1-nu) A S A + nu tr(A S) A), kappa = 5/6, integrated with sqrt(det a0).
A laminated wall takes the strains' components in an orthonormal frame of the surface (the
first vector along xi_1) and its A, B, D, H matrices (:mod:`~tapecoil.models.materials`).

Locking. A thin shell (here R/h = 151 and elements 40 h long) locks in membrane and shear if
those terms are integrated exactly with low-order elements. ``technology`` selects:
  - "psri" (default): partial selective reduced integration on Q2 elements. The membrane and
    shear energies are split into a fraction alpha = min(h^2/h_e^2, 1) integrated with full
    (3 x 3 Gauss) and the rest with reduced (2 x 2) quadrature; bending is integrated fully.
    h_e is the element's size on the 3D mid-surface, the square root of its area measure at the
    quadrature point: h_e^2 = |det dxi/dX| sqrt(det a0), with dxi/dX the Jacobian of the map
    from the reference cell [0, 1]^2 to the parameter cell (half that for the unit triangle)
    and sqrt(det a0) the area element of phi0: on a tape, whose map keeps lengths
    (sqrt(det a0) = 1), an element l1 long and l2 wide has h_e^2 = l1 l2. Every energy is
    reported with exactly the quadrature the solve uses.
  - "full": everything with full quadrature; kept as the locking reference of the
    verification table.
docs/notes/shell-technology.md records the measurements behind the choice (a Hellinger-Reissner
variant with discontinuous resultants was tried and rejected: zero-energy modes).

This module holds the material and the shell's state, kinematics and energy forms; beside it,
:mod:`~tapecoil.models.director` (the director map and its frames), :mod:`~tapecoil.models.quadrature`
(the measures and the PSRI split), :mod:`~tapecoil.models.secant` (the energy-consistent work
over a step), :mod:`~tapecoil.models.nodes` (the numpy side: frames and angles at points,
node-wise state views) and :mod:`~tapecoil.models.solver_terms` (relaxation, rounding scale).
"""

from __future__ import annotations

import ufl

from tapecoil.models import nodes, secant, solver_terms
from tapecoil.models.director import (
    FRAMES,
    angles_from_director,
    director_from_angles,
    director_secant,
    reference_frame,
)
from tapecoil.models.materials import SHEAR_CORRECTION, LaminateMaterial, ShellMaterial, shell_material
from tapecoil.models.nodes import Nodes
from tapecoil.models.quadrature import TECHNOLOGIES, ShellQuadrature

__all__ = [
    "FRAMES",
    "SHEAR_CORRECTION",
    "TECHNOLOGIES",
    "LaminateMaterial",
    "NaghdiShell",
    "Nodes",
    "ShellMaterial",
    "angles_from_director",
    "director_from_angles",
    "director_secant",
    "shell_material",
]


class NaghdiShell:
    """The shell's function space, state, kinematics, energies and forms.

    ``strip`` is a :class:`tapecoil.geometry.meshes.StripMesh`. The unknown ``q`` holds the
    displacement u (3 components, m) and the director angles theta (2 components, rad).
    """

    def __init__(
        self,
        strip,
        material: ShellMaterial,
        technology: str = "psri",
        degree: int = 2,
        director_frame: str = "local",
    ):
        import basix.ufl
        import dolfinx

        if technology not in TECHNOLOGIES:
            raise ValueError(f"technology must be one of {TECHNOLOGIES}, got {technology!r}")
        if director_frame not in FRAMES:
            raise ValueError(f"director_frame must be one of {FRAMES}, got {director_frame!r}")
        self.director_frame = director_frame
        self.strip = strip
        self.mesh = mesh = strip.mesh
        self.material = material
        self.technology = technology
        self.degree = degree

        cell = mesh.basix_cell()
        P = basix.ufl.element("Lagrange", cell, degree, shape=(3,))
        T = basix.ufl.element("Lagrange", cell, degree, shape=(2,))
        parts = [P, T]
        self.W = dolfinx.fem.functionspace(mesh, basix.ufl.mixed_element(parts))
        self.q = dolfinx.fem.Function(self.W, name="state")
        self.dq = ufl.TestFunction(self.W)

        xi = ufl.SpatialCoordinate(mesh)
        self.xi = xi
        self.phi0 = strip.geometry.phi0_ufl(xi)
        J0 = ufl.grad(self.phi0)
        self.J0 = J0
        n0 = ufl.cross(J0[:, 0], J0[:, 1])
        self.n0 = n0 = n0 / ufl.sqrt(ufl.dot(n0, n0))
        self.frame, self.theta_ref = reference_frame(J0, n0, director_frame)
        self.a0 = J0.T * J0
        self.A = ufl.inv(self.a0)
        self.jacobian = ufl.sqrt(ufl.det(self.a0))

        fields = ufl.split(self.q)
        self.u, self.theta = fields[0], fields[1]
        self.d = director_from_angles(self.theta_ref + self.theta, self.frame)
        self.phi = self.phi0 + self.u
        F = ufl.grad(self.phi)
        self.F = F
        self.membrane_strain, self.bending_strain, self.shear_strain = self.strains(F, self.d)

        e, k, g = self.membrane_strain, self.bending_strain, self.shear_strain
        self._psi_m, self._psi_b, self._psi_s = material.energy_densities(self.A, e, k, g)
        self.quadrature = quad = ShellQuadrature(strip, degree, technology, material.h, self.jacobian)
        self.dx, self.dx_reduced, self.ds = quad.dx, quad.dx_reduced, quad.ds
        self.q_full, self.q_reduced = quad.full, quad.reduced
        self.energy_membrane, self.energy_bending, self.energy_shear = self.energy_forms()

    def strains(self, F, d):
        """Membrane, bending and shear strains of a deformation gradient F and director field d."""
        J0 = self.J0
        return (
            0.5 * (F.T * F - self.a0),
            ufl.sym(F.T * ufl.grad(d)) - ufl.sym(J0.T * ufl.grad(self.n0)),
            F.T * d,
        )

    def kinematics(self, state):
        """(u, theta, F, d) of a state-like Function or expression of the space W."""
        u, theta = ufl.as_vector([state[i] for i in range(3)]), ufl.as_vector([state[3], state[4]])
        return u, theta, self.J0 + ufl.grad(u), director_from_angles(self.theta_ref + theta, self.frame)

    def energy_forms(self, weight=1.0):
        """(membrane, bending, shear) energy forms, each integrand times ``weight``.

        Exactly the quadrature rules of the solve (PSRI split included), so that a weighted
        energy (a region's, say) is part of the energy that is minimised.
        """
        return self.quadrature.integrate(weight * self._psi_m, weight * self._psi_b, weight * self._psi_s)

    # the step's secant forms, the numpy side and the solvers' terms are their modules' jobs;
    # bound here because code holding a shell calls them as its methods
    director_variation = secant.director_variation
    energy_secant_forms = secant.energy_secant_forms
    director_frame_numpy = nodes.director_frame_numpy
    angles_of = nodes.angles_of
    rounding_scale = solver_terms.rounding_scale
    relaxation = solver_terms.relaxation

    @property
    def display_offset(self):
        """phi0 + u - (xi_1, xi_2, 0): warps the flat parameter mesh onto the deformed 3D shell."""
        return self.phi - ufl.as_vector([self.xi[0], self.xi[1], 0.0])

    def curvatures(self):
        """Curvatures (longitudinal, transverse) of the deformed mid-surface along xi_1 and xi_2.

        kappa_ii = -phi_,i . d_,i / |phi_,i|^2 (no sum), the second fundamental form of the
        director field; the reference strip has (0, 1/R), positive for the tape's own section.
        """
        F, grad_d = self.F, ufl.grad(self.d)
        return tuple(-ufl.dot(F[:, i], grad_d[:, i]) / ufl.dot(F[:, i], F[:, i]) for i in (0, 1))

    @property
    def strain_energy(self):
        """Total strain energy form, evaluated with the quadrature the solve uses."""
        return self.energy_membrane + self.energy_bending + self.energy_shear

    def residual(self, external_work=None):
        """Residual: the derivative of strain energy - external work in the direction dq."""
        total = self.strain_energy if external_work is None else self.strain_energy - external_work
        return ufl.derivative(total, self.q, self.dq)

    def jacobian_form(self, residual):
        return ufl.derivative(residual, self.q, ufl.TrialFunction(self.W))
