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


FRAMES = ("local", "global")


def director_from_angles(theta, frame):
    """Director d(theta) in the frame (e1, e2, e3), see the module docstring."""
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


def director_secant(theta0, theta1, frame):
    """A 3 x 2 discrete derivative of the director map between the total angles theta0 and theta1.

    Dd_bar (theta1 - theta0) = d(theta1) - d(theta0) holds exactly (Gonzalez's discrete
    gradient, applied to each component of d): the derivative at the midpoint plus a correction
    along the step, which is of second order in the step. Steps below 1e-12 rad take the
    midpoint derivative alone.
    """
    mid = ufl.variable(0.5 * (theta0 + theta1))
    derivative = ufl.diff(director_from_angles(mid, frame), mid)
    step = theta1 - theta0
    length2 = ufl.dot(step, step)
    rest = (
        director_from_angles(theta1, frame) - director_from_angles(theta0, frame) - ufl.dot(derivative, step)
    )
    eps = 1e-24
    weight = ufl.conditional(ufl.gt(length2, eps), 1.0 / ufl.max_value(length2, eps), 0.0)
    return derivative + weight * ufl.outer(rest, step)


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
        self.n0 = n0
        if director_frame == "local":
            self.frame = (t1, t2, n0)
            self.theta_ref = ufl.as_vector([0.0, 0.0])
        else:
            self.frame = tuple(ufl.as_vector(e) for e in np.eye(3))
            self.theta_ref = ufl.as_vector([-ufl.asin(n0[1]), ufl.atan2(n0[0], n0[2])])
        self.a0 = J0.T * J0
        self.A = ufl.inv(self.a0)
        self.jacobian = ufl.sqrt(ufl.det(self.a0))

        fields = ufl.split(self.q)
        self.u, self.theta = fields[0], fields[1]
        self.d = director_from_angles(self.theta_ref + self.theta, self.frame)
        self.phi = self.phi0 + self.u
        F = ufl.grad(self.phi)
        self.F = F
        self.membrane_strain, self.bending_strain, self.shear_strain = self._strains(F, self.d)

        E, nu, h = material.E, material.nu, material.h
        G = material.shear_modulus
        A, dA = self.A, self.jacobian
        e, k, g = self.membrane_strain, self.bending_strain, self.shear_strain
        psi_m = 0.5 * h * ufl.inner(_plane_stress(e, A, E, nu), e)
        psi_b = h**3 / 24 * ufl.inner(_plane_stress(k, A, E, nu), k)
        psi_s = 0.5 * SHEAR_CORRECTION * G * h * ufl.dot(g, ufl.dot(A, g))

        self._psi_m, self._psi_b, self._psi_s = psi_m, psi_b, psi_s
        if technology == "full":
            self._alpha = None
        else:
            # physical element size: reference cell [0, 1]^2 (or the unit triangle) times the
            # area scale sqrt(det a0) of the map to 3D
            area = abs(ufl.JacobianDeterminant(mesh)) * dA
            if mesh.topology.cell_name() != "quadrilateral":
                area = area / 2
            self._alpha = ufl.min_value(h**2 / area, 1.0)
        self.energy_membrane, self.energy_bending, self.energy_shear = self.energy_forms()

    def _strains(self, F, d):
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

    def director_variation(self, q_old):
        """The virtual director Dd_bar dtheta of the step from ``q_old`` to q (see director_secant)."""
        _, theta_old, _, _ = self.kinematics(q_old)
        secant = director_secant(self.theta_ref + theta_old, self.theta_ref + self.theta, self.frame)
        return ufl.dot(secant, ufl.split(self.dq)[1])

    def energy_secant_forms(self, q_old):
        """(membrane, bending, shear) internal virtual work, energy-consistent from q_old to q.

        Each strain is at most quadratic in (F, d), so with the stresses of the mean strain and
        the strain variations at the mean (F, d), and the director varied by its discrete
        derivative, the work in the direction of the step, dq = q - q_old, is exactly the
        change of each energy (Simo and Tarnow 1992; Gonzalez 1996):

            sum(forms)(q - q_old) = E(q) - E(q_old).

        The quadrature (PSRI split included) is that of :meth:`energy_forms`, so the identity
        holds point by point.
        """
        _, _, F0, d0 = self.kinematics(q_old)
        F1, d1 = self.F, self.d
        strains = [0.5 * (a + b) for a, b in zip(self._strains(F0, d0), self._strains(F1, d1), strict=True)]
        du = ufl.split(self.dq)[0]
        dF, dd = ufl.grad(du), self.director_variation(q_old)
        F, d, grad_d = 0.5 * (F0 + F1), 0.5 * (d0 + d1), 0.5 * (ufl.grad(d0) + ufl.grad(d1))
        de = ufl.sym(F.T * dF)
        dk = ufl.sym(F.T * ufl.grad(dd) + dF.T * grad_d)
        dg = F.T * dd + dF.T * d
        m = self.material
        A, E, nu, h = self.A, m.E, m.nu, m.h
        membrane = h * ufl.inner(_plane_stress(strains[0], A, E, nu), de)
        bending = h**3 / 12 * ufl.inner(_plane_stress(strains[1], A, E, nu), dk)
        shear = SHEAR_CORRECTION * m.shear_modulus * h * ufl.dot(ufl.dot(A, strains[2]), dg)
        return self._integrate(membrane, bending, shear)

    def energy_forms(self, weight=1.0):
        """(membrane, bending, shear) energy forms, each integrand times ``weight``.

        Exactly the quadrature rules of the solve (PSRI split included), so that a weighted
        energy (a region's, say) is part of the energy that is minimised.
        """
        return self._integrate(weight * self._psi_m, weight * self._psi_b, weight * self._psi_s)

    def _integrate(self, membrane, bending, shear):
        """Membrane, bending and shear densities as forms with the solve's quadrature (PSRI split)."""
        dA = self.jacobian
        if self._alpha is None:
            return membrane * dA * self.dx, bending * dA * self.dx, shear * dA * self.dx
        a = self._alpha

        def split(density):
            return a * density * dA * self.dx + (1 - a) * density * dA * self.dx_reduced

        return split(membrane), bending * dA * self.dx, split(shear)

    # -- state access --------------------------------------------------------------------
    def director_frame_numpy(self, xi: np.ndarray):
        """The director frame (e1, e2, e3) and reference angles (2, n) at parameter points."""
        local = self.strip.geometry.frame(xi)
        if self.director_frame == "local":
            return local, np.zeros((2, xi.shape[1]))
        n = xi.shape[1]
        frame = tuple(np.tile(e[:, None], n) for e in np.eye(3))
        n0 = local[2]
        return frame, np.vstack([-np.arcsin(np.clip(n0[1], -1, 1)), np.arctan2(n0[0], n0[2])])

    def angles_of(self, d: np.ndarray, xi: np.ndarray, rotation_near: float = 0.0) -> np.ndarray:
        """Unknown angles theta (2, n) that give the directors d (3, n) at parameter points xi.

        The unbounded theta_1 is taken on the branch nearest ``rotation_near`` [rad].
        """
        frame, ref = self.director_frame_numpy(xi)
        return angles_from_director(d, frame, theta1_near=ref[1] + rotation_near) - ref

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

    def rounding_scale(self):
        """The magnitude of what each state component is added to, for the solver's round-off
        floor: |phi0| for the displacement (the position phi0 + u rounds to eps |phi0 + u|),
        1 for the director angles (the director's components, of size 1, round to eps)."""
        import dolfinx

        scale = dolfinx.fem.Function(self.W)
        V, dofs = self.W.sub(0).collapse()
        position = dolfinx.fem.Function(V)
        position.interpolate(lambda x: np.abs(self.strip.geometry.phi0(x)))
        scale.x.array[dofs] = position.x.array
        _, angle_dofs = self.W.sub(1).collapse()
        scale.x.array[angle_dofs] = 1.0
        return scale

    def relaxation(self, length_scale: float):
        """Viscous term for pseudo-transient relaxation: (coefficient, previous state, form).

        coefficient * [(u - u_prev).du + length_scale^2 (theta - theta_prev).dtheta] over the
        reference area; with the coefficient 0 it vanishes.
        """
        import dolfinx

        coefficient = dolfinx.fem.Constant(self.mesh, 0.0)
        previous = dolfinx.fem.Function(self.W)
        prev = ufl.split(previous)
        du, dtheta = ufl.split(self.dq)[0], ufl.split(self.dq)[1]
        form = (
            coefficient
            * (ufl.dot(self.u - prev[0], du) + length_scale**2 * ufl.dot(self.theta - prev[1], dtheta))
            * self.jacobian
            * self.dx
        )
        return coefficient, previous, form

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


class Nodes:
    """Node-wise numpy views of a shell state: positions, directors and the W-dofs behind them.

    All components of u and theta live on the same Q2 nodes; ``space`` is the scalar Q2 space on
    those nodes (local and ghost, in its own order) and ``u_dofs`` (n, 3), ``theta_dofs`` (n, 2)
    give the W-dof of each component at each node. Computations on these arrays are rank-local and,
    done on ghosts as on owners from the same values, give every rank the same values.
    """

    def __init__(self, model: NaghdiShell):
        from tapecoil.core import compat

        W = model.W
        spaces_maps = [compat.collapse(W.sub(0).sub(i)) for i in range(3)]
        spaces_maps += [compat.collapse(W.sub(1).sub(i)) for i in range(2)]
        self.space = spaces_maps[0][0]
        xi = self.space.tabulate_dof_coordinates()
        for space, _ in spaces_maps[1:]:  # the same node order in every collapsed component
            if not np.array_equal(space.tabulate_dof_coordinates(), xi):
                raise RuntimeError("collapsed shell components do not share their node order")
        self.u_dofs = np.column_stack([m for _, m in spaces_maps[:3]])
        self.theta_dofs = np.column_stack([m for _, m in spaces_maps[3:]])
        if self.u_dofs.shape != (xi.shape[0], 3) or self.theta_dofs.shape != (xi.shape[0], 2):
            raise RuntimeError(f"unexpected collapsed dof maps {self.u_dofs.shape}, {self.theta_dofs.shape}")
        self.xi = xi[:, :2].T.copy()
        self.reference = model.strip.geometry.phi0(self.xi)
        self.frame, self.theta_ref = model.director_frame_numpy(self.xi)

    def positions(self, q: np.ndarray) -> np.ndarray:
        """Mid-surface positions (3, n) for the W-dof array ``q``."""
        return self.reference + q[self.u_dofs].T

    def directors(self, q: np.ndarray) -> np.ndarray:
        """Unit directors (3, n) for the W-dof array ``q``."""
        t0, t1 = self.theta_ref + q[self.theta_dofs].T
        e1, e2, e3 = self.frame
        return np.cos(t0) * np.sin(t1) * e1 - np.sin(t0) * e2 + np.cos(t0) * np.cos(t1) * e3
