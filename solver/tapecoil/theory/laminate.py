"""The tape's wall as a plate: classical lamination theory and the bending rigidities of the formulas.

A wall is described by its stiffness matrices in the tape's axes (1 along the length, 2 across
the width, z through the thickness along the shell's reference normal), Voigt order
(11, 22, 12) with the engineering shear strain 2 e_12:

    N = A eps + B kappa,   M = B eps + D kappa,   Q = H gamma,

A [N/m], B [N], D [N m] 3 x 3 and H [N/m] 2 x 2 (transverse shear, order (13, 23), the shear
correction included). An isotropic wall is the case A = h Q, B = 0, D = h^3/12 Q. A laminate's
matrices come from its plies (Jones, *Mechanics of Composite Materials*, ch. 4): each ply's
plane-stress stiffness Q turned by the ply angle, integrated through the thickness.

The plate formulas of the physics brief need the bending rigidities of a wall free of in-plane
forces (N = 0: the flattened coil's membrane strains relax), D* = D - B A^-1 B, of which D11
(along), D22 (across) and D12 enter (Sec. 10); :class:`Bending` carries them.

numpy only, so that the theory and the configuration use it without DOLFINx.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

SHEAR_CORRECTION = 5.0 / 6.0
"""Transverse shear correction factor of a Reissner-Mindlin wall (Reissner's 5/6)."""


@dataclass(frozen=True)
class Bending:
    """Bending rigidities of a wall free of in-plane forces [N m]: D11 along the tape, D22
    across it, D12 their coupling, D66 the twisting one (physics brief Sec. 10)."""

    D11: float
    D12: float
    D22: float
    D66: float

    @classmethod
    def isotropic(cls, D: float, nu: float) -> Bending:
        """D11 = D22 = D, D12 = nu D, D66 = (1 - nu) D / 2."""
        return cls(D, nu * D, D, 0.5 * (1 - nu) * D)

    @property
    def beta(self) -> float:
        """The orthotropic ratio D11 / D22 of Eq. 3.5 [-] (1 for an isotropic wall)."""
        return self.D11 / self.D22

    @property
    def is_isotropic(self) -> bool:
        """True when D11 = D22 and D66 = (D11 - D12)/2 to round-off."""
        scale = abs(self.D11)
        return (
            abs(self.D22 - self.D11) <= 1e-12 * scale
            and abs(2 * self.D66 - (self.D11 - self.D12)) <= 1e-12 * scale
        )


def plane_stress_stiffness(E: float, nu: float) -> np.ndarray:
    """Isotropic plane-stress stiffness Q (3 x 3, Voigt 11, 22, 12 with engineering shear) [Pa]."""
    c = E / (1 - nu**2)
    return c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 0.5 * (1 - nu)]])


def ply_stiffness(E1: float, E2: float, nu12: float, G12: float, angle: float) -> np.ndarray:
    """Plane-stress stiffness Q-bar [Pa] of an orthotropic ply whose fibres (axis 1: E1) lie at
    ``angle`` [rad] from the tape's length axis, turned towards its width axis."""
    nu21 = nu12 * E2 / E1
    d = 1 - nu12 * nu21
    Q11, Q22, Q12, Q66 = E1 / d, E2 / d, nu12 * E2 / d, G12
    m, n = math.cos(angle), math.sin(angle)
    m2, n2 = m * m, n * n
    q11 = Q11 * m2 * m2 + 2 * (Q12 + 2 * Q66) * m2 * n2 + Q22 * n2 * n2
    q22 = Q11 * n2 * n2 + 2 * (Q12 + 2 * Q66) * m2 * n2 + Q22 * m2 * m2
    q12 = (Q11 + Q22 - 4 * Q66) * m2 * n2 + Q12 * (m2 * m2 + n2 * n2)
    q66 = (Q11 + Q22 - 2 * Q12 - 2 * Q66) * m2 * n2 + Q66 * (m2 * m2 + n2 * n2)
    q16 = (Q11 - Q12 - 2 * Q66) * m2 * m * n + (Q12 - Q22 + 2 * Q66) * m * n2 * n
    q26 = (Q11 - Q12 - 2 * Q66) * m * n2 * n + (Q12 - Q22 + 2 * Q66) * m2 * m * n
    return np.array([[q11, q12, q16], [q12, q22, q26], [q16, q26, q66]])


def ply_shear_stiffness(G13: float, G23: float, angle: float) -> np.ndarray:
    """Transverse shear stiffness [Pa] of a ply at ``angle``, order (13, 23) in the tape's axes."""
    m, n = math.cos(angle), math.sin(angle)
    return np.array(
        [[G13 * m * m + G23 * n * n, (G13 - G23) * m * n], [(G13 - G23) * m * n, G13 * n * n + G23 * m * m]]
    )


@dataclass(frozen=True)
class Ply:
    """One ply of a laminate: its through-thickness interval [z0, z1] [m] and its plane-stress
    stiffness Q [Pa] in the tape's axes (for the stresses at a depth z)."""

    z0: float
    z1: float
    Q: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class Wall:
    """The tape's wall: A, B, D, H (see the module docstring), its thickness h [m], and the
    plies through the thickness (one homogeneous ply for a wall given by E and nu, or by its
    matrices: then Q = 12 D / h^3, the homogeneous wall of the same bending stiffness)."""

    A: np.ndarray = field(repr=False)
    B: np.ndarray = field(repr=False)
    D: np.ndarray = field(repr=False)
    H: np.ndarray = field(repr=False)
    h: float
    plies: tuple[Ply, ...] = field(repr=False)

    @classmethod
    def isotropic(cls, E: float, nu: float, h: float) -> Wall:
        """A homogeneous isotropic wall (shear modulus E / (2 (1 + nu)))."""
        Q = plane_stress_stiffness(E, nu)
        G = E / (2 * (1 + nu))
        return cls(
            h * Q,
            np.zeros((3, 3)),
            h**3 / 12 * Q,
            SHEAR_CORRECTION * G * h * np.eye(2),
            h,
            (Ply(-h / 2, h / 2, Q),),
        )

    @classmethod
    def from_plies(cls, E1, E2, nu12, G12, G13, G23, angles, thicknesses) -> Wall:
        """A laminate of plies listed from the face at z = -h/2 up: per ply its material
        (E1, E2, G12, G13, G23 [Pa], nu12 [-]), fibre angle [rad] from the length axis and
        thickness [m]. Each material argument is a sequence of one value per ply."""
        h = float(sum(thicknesses))
        z = -h / 2
        A, B, D, H = (np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((2, 2)))
        plies = []
        for e1, e2, v12, g12, g13, g23, angle, t in zip(
            E1, E2, nu12, G12, G13, G23, angles, thicknesses, strict=True
        ):
            Q = ply_stiffness(e1, e2, v12, g12, angle)
            z0, z1 = z, z + t
            A += Q * (z1 - z0)
            B += Q * (z1**2 - z0**2) / 2
            D += Q * (z1**3 - z0**3) / 3
            H += ply_shear_stiffness(g13, g23, angle) * (z1 - z0)
            plies.append(Ply(z0, z1, Q))
            z = z1
        # a symmetric layup's B is zero but for round-off of the sums: make it exactly zero
        B[np.abs(B) <= 1e-12 * h * np.abs(A).max()] = 0.0
        return cls(A, B, D, SHEAR_CORRECTION * H, h, tuple(plies))

    @classmethod
    def from_matrices(cls, A, B, D, H, h: float) -> Wall:
        """A wall given by its matrices (A, B, D 3 x 3; H 2 x 2, the shear correction included)."""
        A, B, D, H = (np.asarray(x, dtype=float) for x in (A, B, D, H))
        return cls(A, B, D, H, h, (Ply(-h / 2, h / 2, 12 * D / h**3),))

    @property
    def stiffness(self) -> np.ndarray:
        """The 6 x 6 matrix [[A, B], [B, D]] relating (N, M) to (eps, kappa)."""
        return np.block([[self.A, self.B], [self.B, self.D]])

    @property
    def reduced_bending(self) -> np.ndarray:
        """D* = D - B A^-1 B [N m]: the bending stiffness with the in-plane forces relaxed (N = 0)."""
        return self.D - self.B @ np.linalg.solve(self.A, self.B)

    @property
    def bending(self) -> Bending:
        """The rigidities D11, D12, D22, D66 of :attr:`reduced_bending`."""
        d = self.reduced_bending
        return Bending(float(d[0, 0]), float(d[0, 1]), float(d[1, 1]), float(d[2, 2]))

    @property
    def axial_stiffness(self) -> float:
        """1 / (A^-1)_11 [N/m]: the force per unit width that stretches the wall along the tape by
        a unit strain with its width free to contract (E h for an isotropic wall)."""
        return float(1.0 / np.linalg.inv(self.A)[0, 0])

    @property
    def axial_modulus(self) -> float:
        """:attr:`axial_stiffness` / h [Pa]: the modulus of a strip pulled along its length with
        its width free to contract (E for an isotropic wall), the E of beam formulas."""
        return self.axial_stiffness / self.h

    def stiffness_at(self, z: float) -> np.ndarray:
        """Q [Pa] of the ply at depth z (the lower ply at an interface; z = +-h/2 is a face's)."""
        for ply in self.plies:
            if z <= ply.z1 + 1e-12 * self.h:
                return ply.Q
        return self.plies[-1].Q

    def check(self) -> None:
        """Raise ValueError unless the stiffness is symmetric positive definite (a stable wall)."""
        for name, K in (("[[A, B], [B, D]]", self.stiffness), ("H", self.H)):
            if not np.allclose(K, K.T, rtol=1e-10, atol=0.0):
                raise ValueError(f"the wall's {name} is not symmetric")
            scale = np.abs(np.diag(K))
            if np.any(scale <= 0) or np.linalg.eigvalsh(K / np.sqrt(np.outer(scale, scale))).min() <= 1e-12:
                raise ValueError(
                    f"the wall's {name} is not positive definite: it stores no energy in some strain"
                )
