"""Nonlinear Naghdi (Reissner-Mindlin) shell on a flat parameter domain mapped to 3D.

Kinematics. The reference mid-surface is phi0(xi) (geometry module) with covariant basis
J0 = grad phi0, metric a0 = J0^T J0 and unit normal n0. An orthonormal frame (t1, t2, n0) with
t1 along the first parameter direction carries the director

    d(theta) = cos(theta_0) sin(theta_1) t1 - sin(theta_0) t2 + cos(theta_0) cos(theta_1) n0,

a rotation by theta_1 about t2 after a rotation by theta_0 about t1. theta_1 is the rotation
about the tape's width axis: coiling through many turns is an unbounded, regular theta_1. The
map is singular only at |theta_0| = pi/2 (director along t2), which a tape never reaches: the
flattening of the section turns the director by at most alpha/2 about t1.

Strains (covariant, with phi = phi0 + u, F = grad phi):
    membrane  e = (F^T F - a0) / 2
    bending   k = sym(F^T grad d) - sym(J0^T grad n0)
    shear     g = F^T d            (J0^T n0 = 0)
Isotropic plane-stress resultants use the contravariant metric A = a0^-1; the energy per unit
reference area is h/2 C(e):e + h^3/24 C(k):k + kappa G h / 2 g.A.g with
C(S) = E/(1-nu^2) ((1-nu) A S A + nu tr(A S) A), kappa = 5/6, integrated with sqrt(det a0).

Locking. A thin shell (here R/h = 151 and elements 40 h long) locks in membrane and shear if
those terms are integrated exactly with low-order elements. ``technology`` selects:
  - "psri" (default): partial selective reduced integration on Q2 elements. The membrane and
    shear energies are split into a fraction h^2/h_e^2 integrated with full (3 x 3 Gauss) and
    the rest with reduced (2 x 2) quadrature; bending is integrated fully. Every energy is
    reported with exactly the quadrature the solve uses.
  - "full": everything with full quadrature; kept as the locking reference of the
    verification table.
docs/shell-technology.md records the measurements behind the choice (a Hellinger-Reissner
variant with discontinuous resultants was tried and rejected: zero-energy modes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl

TECHNOLOGIES = ("full", "psri")
SHEAR_CORRECTION = 5.0 / 6.0


@dataclass(frozen=True)
class ShellMaterial:
    """Isotropic linear elastic shell: Young's modulus E [Pa], Poisson ratio nu [-], thickness h [m]."""

    E: float
    nu: float
    h: float

    @property
    def shear_modulus(self) -> float:
        return self.E / (2 * (1 + self.nu))


def _plane_stress(S, A, E: float, nu: float):
    """Contravariant stress-like tensor C(S) of a covariant strain S, isotropic plane stress."""
    return E / (1 - nu**2) * ((1 - nu) * ufl.dot(ufl.dot(A, S), A) + nu * ufl.tr(ufl.dot(A, S)) * A)


def director_from_angles(theta, frame):
    """Director d(theta) in the frame (t1, t2, n0), see the module docstring."""
    t1, t2, n0 = frame
    c0, s0 = ufl.cos(theta[0]), ufl.sin(theta[0])
    return c0 * ufl.sin(theta[1]) * t1 - s0 * t2 + c0 * ufl.cos(theta[1]) * n0


def angles_from_director(d: np.ndarray, frame: tuple[np.ndarray, ...], theta1_near: np.ndarray | float = 0.0):
    """Angles (theta_0, theta_1) of unit directors d (3, n) in frames (3, n) each; numpy.

    theta_1 is defined up to multiples of 2 pi: the branch nearest ``theta1_near`` is returned,
    so that rotations through several turns stay continuous.
    """
    t1, t2, n0 = frame
    dt1, dt2, dn = (np.einsum("in,in->n", d, v) for v in (t1, t2, n0))
    theta0 = -np.arcsin(np.clip(dt2, -1.0, 1.0))
    theta1 = np.arctan2(dt1, dn)
    theta1 = theta1 + 2 * np.pi * np.round((theta1_near - theta1) / (2 * np.pi))
    return np.vstack([theta0, theta1])


class NaghdiShell:
    """The shell's function space, state, kinematics, energies and forms.

    ``strip`` is a :class:`tapecoil.geometry.StripMesh`. The unknown ``q`` holds the
    displacement u (3 components, m) and the director angles theta (2 components, rad).
    """

    def __init__(self, strip, material: ShellMaterial, technology: str = "psri", degree: int = 2):
        import basix.ufl
        import dolfinx

        if technology not in TECHNOLOGIES:
            raise ValueError(f"technology must be one of {TECHNOLOGIES}, got {technology!r}")
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

        # quadrature: 'full' integrates the polynomial part exactly on the affine parameter
        # mesh; 'reduced' is one Gauss point fewer per direction
        self.q_full = 2 * degree + 1
        self.q_reduced = 2 * degree - 1
        self.dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": self.q_full})
        self.dx_reduced = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": self.q_reduced})
        self.ds = ufl.Measure(
            "ds", domain=mesh, subdomain_data=strip.facet_tags, metadata={"quadrature_degree": self.q_full}
        )

        xi = ufl.SpatialCoordinate(mesh)
        self.xi = xi
        self.phi0 = strip.geometry.phi0_ufl(xi)
        J0 = ufl.grad(self.phi0)
        self.J0 = J0
        n0 = ufl.cross(J0[:, 0], J0[:, 1])
        n0 = n0 / ufl.sqrt(ufl.dot(n0, n0))
        t1 = J0[:, 0] / ufl.sqrt(ufl.dot(J0[:, 0], J0[:, 0]))
        t2 = ufl.cross(n0, t1)
        self.frame = (t1, t2, n0)
        self.n0 = n0
        self.a0 = J0.T * J0
        self.A = ufl.inv(self.a0)
        self.jacobian = ufl.sqrt(ufl.det(self.a0))

        fields = ufl.split(self.q)
        self.u, self.theta = fields[0], fields[1]
        self.d = director_from_angles(self.theta, self.frame)
        self.phi = self.phi0 + self.u
        F = ufl.grad(self.phi)
        self.F = F
        self.membrane_strain = 0.5 * (F.T * F - self.a0)
        self.bending_strain = ufl.sym(F.T * ufl.grad(self.d)) - ufl.sym(J0.T * ufl.grad(n0))
        self.shear_strain = F.T * self.d

        E, nu, h = material.E, material.nu, material.h
        G = material.shear_modulus
        A, dA = self.A, self.jacobian
        e, k, g = self.membrane_strain, self.bending_strain, self.shear_strain
        psi_m = 0.5 * h * ufl.inner(_plane_stress(e, A, E, nu), e)
        psi_b = h**3 / 24 * ufl.inner(_plane_stress(k, A, E, nu), k)
        psi_s = 0.5 * SHEAR_CORRECTION * G * h * ufl.dot(g, ufl.dot(A, g))

        self.energy_bending = psi_b * dA * self.dx
        if technology == "full":
            self.energy_membrane = psi_m * dA * self.dx
            self.energy_shear = psi_s * dA * self.dx
        else:
            # physical element size: reference cell [0, 1]^2 (or the unit triangle) times the
            # area scale sqrt(det a0) of the map to 3D
            area = abs(ufl.JacobianDeterminant(mesh)) * dA
            if mesh.topology.cell_name() != "quadrilateral":
                area = area / 2
            alpha = ufl.min_value(h**2 / area, 1.0)
            self.energy_membrane = alpha * psi_m * dA * self.dx + (1 - alpha) * psi_m * dA * self.dx_reduced
            self.energy_shear = alpha * psi_s * dA * self.dx + (1 - alpha) * psi_s * dA * self.dx_reduced

    # -- state access --------------------------------------------------------------------
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
