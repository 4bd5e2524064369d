"""The shell's wall laws: the energy and virtual work per unit reference area of the strains.

Both laws take the covariant strains of :class:`~tapecoil.models.shell.NaghdiShell` (membrane e,
bending k, shear g, components in the parameter coordinates xi) and the contravariant metric
A = a0^-1 of the reference surface:

- :class:`ShellMaterial`: a homogeneous isotropic wall (E, nu, h), written with the metric
  alone (the shell module's docstring);
- :class:`LaminateMaterial`: any wall given by its stiffness matrices A, B, D, H in the tape's
  axes (:class:`tapecoil.theory.laminate.Wall`: a laminate by classical lamination theory, or
  matrices as given). The strains are taken to an orthonormal frame (c1, c2) of the reference
  surface, c1 along xi_1 (the tape's length) and c2 orthogonal to it in the surface:
  c_a = J0 p_a with p_1 = e_1 / sqrt(a0_11), p_2 = (e_2 - a0_12 / a0_11 e_1) / sqrt(det a0 / a0_11),
  so that the components are E = P^T e P and gamma = P^T g (P = [p_1 p_2], P P^T = A).

The coupling B of membrane and bending is counted with the bending energy, so that the PSRI
split (membrane and shear partly under-integrated, bending fully) leaves it whole.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl

from tapecoil.theory.laminate import SHEAR_CORRECTION, Wall

__all__ = ["SHEAR_CORRECTION", "LaminateMaterial", "ShellMaterial", "shell_material"]


@dataclass(frozen=True)
class ShellMaterial:
    """Isotropic linear elastic shell: Young's modulus E [Pa], Poisson ratio nu [-], thickness h [m]."""

    E: float
    nu: float
    h: float

    @property
    def shear_modulus(self) -> float:
        return self.E / (2 * (1 + self.nu))

    def energy_densities(self, A, e, k, g):
        """Membrane, bending and shear energy per unit reference area of the covariant strains
        (e, k, g), with the contravariant metric A (the shell module's docstring)."""
        E, nu, h = self.E, self.nu, self.h
        return (
            0.5 * h * ufl.inner(_plane_stress(e, A, E, nu), e),
            h**3 / 24 * ufl.inner(_plane_stress(k, A, E, nu), k),
            0.5 * SHEAR_CORRECTION * self.shear_modulus * h * ufl.dot(g, ufl.dot(A, g)),
        )

    def work_densities(self, A, strains, variations):
        """Membrane, bending and shear virtual work per unit reference area of the resultants of
        the strains (e, k, g) on the strain variations (de, dk, dg)."""
        (e, k, g), (de, dk, dg) = strains, variations
        E, nu, h = self.E, self.nu, self.h
        return (
            h * ufl.inner(_plane_stress(e, A, E, nu), de),
            h**3 / 12 * ufl.inner(_plane_stress(k, A, E, nu), dk),
            SHEAR_CORRECTION * self.shear_modulus * h * ufl.dot(ufl.dot(A, g), dg),
        )


def _plane_stress(S, A, E: float, nu: float):
    """Contravariant stress-like tensor C(S) of a covariant strain S, isotropic plane stress."""
    return E / (1 - nu**2) * ((1 - nu) * ufl.dot(ufl.dot(A, S), A) + nu * ufl.tr(ufl.dot(A, S)) * A)


class LaminateMaterial:
    """A wall of stiffness matrices (see the module docstring): ``wall`` is a
    :class:`tapecoil.theory.laminate.Wall`, its thickness h [m] the shell's."""

    def __init__(self, wall: Wall):
        self.wall = wall
        self.h = wall.h
        as_ufl = lambda M: ufl.as_matrix(np.asarray(M, dtype=float).tolist())  # noqa: E731
        self._A, self._B, self._D, self._H = (as_ufl(M) for M in (wall.A, wall.B, wall.D, wall.H))
        self._coupled = bool(np.any(wall.B != 0.0))

    @staticmethod
    def _frame(A):
        """P = [p_1 p_2] of the module docstring, from the contravariant metric A."""
        a0 = ufl.inv(A)
        s1 = ufl.sqrt(a0[0, 0])
        s2 = ufl.sqrt(ufl.det(a0) / a0[0, 0])
        return ufl.as_matrix([[1 / s1, -a0[0, 1] / (a0[0, 0] * s2)], [0, 1 / s2]])

    @staticmethod
    def _voigt(P, S):
        """(S_11, S_22, 2 S_12) of a covariant tensor S in the orthonormal frame."""
        E = P.T * S * P
        return ufl.as_vector([E[0, 0], E[1, 1], 2 * E[0, 1]])

    def _local(self, P, e, k, g):
        """The strains (e, k, g) in the frame P: two Voigt vectors and the shear vector."""
        return self._voigt(P, e), self._voigt(P, k), P.T * g

    def energy_densities(self, A, e, k, g):
        """Membrane, bending (with the coupling B) and shear energy per unit reference area."""
        eps, kap, gam = self._local(self._frame(A), e, k, g)
        bending = 0.5 * ufl.dot(kap, self._D * kap)
        if self._coupled:
            bending += ufl.dot(eps, self._B * kap)
        return 0.5 * ufl.dot(eps, self._A * eps), bending, 0.5 * ufl.dot(gam, self._H * gam)

    def work_densities(self, A, strains, variations):
        """Virtual work of the resultants of (e, k, g) on (de, dk, dg), parted as the energies."""
        P = self._frame(A)
        eps, kap, gam = self._local(P, *strains)
        deps, dkap, dgam = self._local(P, *variations)
        bending = ufl.dot(self._D * kap, dkap)
        if self._coupled:
            bending += ufl.dot(self._B * eps, dkap) + ufl.dot(self._B * kap, deps)
        return ufl.dot(self._A * eps, deps), bending, ufl.dot(self._H * gam, dgam)


def shell_material(config):
    """The wall law of a configuration: :class:`ShellMaterial` of tape.E, tape.nu, tape.h for an
    isotropic tape, :class:`LaminateMaterial` of its [laminate] otherwise."""
    tp = config.tape
    if config.laminate.kind == "isotropic":
        return ShellMaterial(tp.E, tp.nu, tp.h)
    return LaminateMaterial(config.wall)
