"""Plate and section formulas of a tape spring: rigidity, energy densities, moments, stresses.

Physics brief sections 3, 4 and 7; SI units.

Sign convention for stresses: z is the distance from the mid-surface, positive on the face
away from the hub (the outer face of the coil). In opposite-sense coiling both the coil
curvature and the flattening of the cross-section stretch that face, so the outer face is in
tension in both directions and the inner face in compression.
"""

from __future__ import annotations

import math

import numpy as np

from tapecoil.theory.laminate import Bending


def flexural_rigidity(E: float, h: float, nu: float) -> float:
    """Plate flexural rigidity D = E h^3 / (12 (1 - nu^2)) [N m]."""
    return E * h**3 / (12 * (1 - nu**2))


SENSES = ("opposite", "equal")
"""The coiling senses, for the theory and the hub's frame (the configuration, which the theory
imports, lists them in its own allowed values)."""


def sense_sign(sense: str) -> float:
    """+1 for opposite-sense coiling, -1 for equal sense: the sign of the nu terms of the coil's
    energy and stresses (physics brief Sec. 10: the curvature changes 1/rho of the coil and
    1/R of the flattening have the same sign in opposite sense, opposite signs in equal sense)."""
    if sense not in SENSES:
        raise ValueError(f"coiling sense must be one of {SENSES}, got {sense!r}")
    return 1.0 if sense == "opposite" else -1.0


def opposite_sense_energy_density(D: float, nu: float, R: float) -> float:
    """mu = D (1 + nu) / R^2 [J/m^2]: energy per unit area of the opposite-sense coil of radius R."""
    return D * (1 + nu) / R**2


def coil_energy_at_R(bending: Bending, R: float, sense: str = "opposite") -> float:
    """w(R) [J/m^2]: Seffen and Pellegrino's mu for either sense, (D11 + D22 +- 2 D12) / (2 R^2);
    D (1 +- nu) / R^2 for an isotropic wall (the D (1 -+ nu) of Eq. 2.17)."""
    return float(energy_density(R, R, bending, sense))


def energy_density(
    rho: float | np.ndarray, R: float, bending: Bending, sense: str = "opposite"
) -> float | np.ndarray:
    """Kirchhoff plate energy per unit area of a flattened section coiled to radius rho [J/m^2].

    w(rho) = (1/2) (D11/rho^2 + D22/R^2 +- 2 D12 / (rho R)), + for opposite sense, - for equal
    sense (physics brief Sec. 3 and 10; (D/2)(1/rho^2 + 1/R^2 +- 2 nu/(rho R)) for an isotropic
    wall); w(R) = :func:`coil_energy_at_R`.
    """
    d = bending
    return 0.5 * (d.D11 / rho**2 + d.D22 / R**2 + sense_sign(sense) * 2 * d.D12 / (rho * R))


def arc_second_moment(R: float, alpha: float, h: float) -> float:
    """Second moment of area of a thin circular-arc section about its centroidal axis [m^4].

    The axis is parallel to the chord (bending about the tape's width axis). Thin-wall form
    I = R^3 h (beta + sin(beta) cos(beta) - 2 sin(beta)^2 / beta), beta = alpha/2, plus the
    plate term b h^3 / 12 of the wall's own bending.
    """
    beta = alpha / 2
    s, c = math.sin(beta), math.cos(beta)
    return R**3 * h * (beta + s * c - 2 * s * s / beta) + R * alpha * h**3 / 12


def fold_moment(bending: Bending, alpha: float, sense: str = "opposite") -> float:
    """Steady moment of a localised fold, alpha (sqrt(D11 D22) +- D12) [N m], + in the opposite
    sense, - in the equal sense.

    Wuest (1954); Seffen and Pellegrino (1999): (1 + nu) D alpha and (1 - nu) D alpha for an
    isotropic wall (in magnitude). A fold of radius rho turned by an angle stores b w(rho) rho
    per radian, w of either sense (:func:`energy_density`); its minimum over rho, at
    R sqrt(D11 / D22) in both senses, is the moment (physics brief Sec. 10). It is the moment
    plateau after the snap when a tape is bent so that its cross-section flattens.
    """
    d = bending
    return alpha * (math.sqrt(d.D11 * d.D22) + sense_sign(sense) * d.D12)


def fold_radius(bending: Bending, R: float) -> float:
    """Radius of a localised opposite-sense fold, R sqrt(D11 / D22) [m] (R for an isotropic wall)."""
    return R * math.sqrt(bending.beta)


def coil_stresses(
    rho: float | np.ndarray, R: float, Q: np.ndarray, z: float, sense: str = "opposite"
) -> tuple[float, float]:
    """Plane-stress bending stresses (sigma_x, sigma_y) [Pa] at z in a coil of radius rho.

    ``Q`` is the plane-stress stiffness at z (:func:`~tapecoil.theory.laminate.plane_stress_stiffness`
    for an isotropic wall, :meth:`~tapecoil.theory.laminate.Wall.stiffness_at` for a laminate's
    ply). Opposite sense: curvature changes +1/rho (longitudinal) and +1/R (transverse,
    flattening), eps_x = z/rho, eps_y = z/R, no twist. Equal sense: the flattening's is -1/R,
    eps_y = -z/R; for an isotropic wall sigma_x = c (1/rho - nu/R), sigma_y = -c (1/R - nu/rho)
    (physics brief Sec. 10). The membrane strains are those of a symmetric wall (none). z > 0
    on the outer face (see the module docstring); use z = +-h/2.
    """
    s = sense_sign(sense)
    ex, ey = z / np.asarray(rho, dtype=float), s * z / R
    sx = Q[0, 0] * ex + Q[0, 1] * ey
    sy = Q[1, 0] * ex + Q[1, 1] * ey
    if np.ndim(sx) == 0:
        return float(sx), float(sy)
    return sx, sy


def ploy_length(width: float, R: float, h: float, beta: float = 1.0) -> float:
    """Eq. 3.5, dimensionally consistent reading: L_p = w^2 / (sqrt(70) beta^(1/4) sqrt(R h)) [m].

    As printed (R^2 t^(1/2) in the denominator) the formula is not a length. beta = 1 for an
    isotropic tape. The prefactor is uncertain: evaluate it for both the arc width and the
    projected width and compare with the measured transition length.
    """
    return width**2 / (math.sqrt(70) * beta**0.25 * math.sqrt(R * h))
