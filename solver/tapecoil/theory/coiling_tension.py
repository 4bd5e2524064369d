"""The pull needed to coil a tape: the regimes of r_c / R and their laws (physics brief section 5)."""

from __future__ import annotations

import math

import numpy as np

from tapecoil.theory.coil_geometry import coil_radius_during_deployment
from tapecoil.theory.laminate import Bending

UNIQUENESS_LIMIT = 3.424
"""r_c/R above which coiling is tension-dominated; between 1 and this, loss of uniqueness."""


def coiling_regime(r_c: float, R: float) -> str:
    """'bending' (r_c/R <= 1), 'non-unique' (1 < r_c/R < 3.424) or 'tension' (>= 3.424)."""
    ratio = r_c / R
    if ratio <= 1:
        return "bending"
    return "non-unique" if ratio < UNIQUENESS_LIMIT else "tension"


def coiling_tension_bending(bending: Bending, alpha: float, R: float, r_c: float) -> float:
    """Eq. 2.6: T = (b / 2)(D11/r_c^2 - D22/R^2) [N], b = R alpha; (D b / 2)(1/r_c^2 - 1/R^2) =
    (D alpha / (2R)) ((R/r_c)^2 - 1) for an isotropic wall (physics brief Sec. 5 and 10).

    The configurational-force balance T = M kappa - U of a flattened coil of radius r_c.
    """
    return R * alpha / 2 * (bending.D11 / r_c**2 - bending.D22 / R**2)


def coiling_tension_tension_dominated(bending: Bending, alpha: float, R: float, r_c: float) -> float:
    """Eq. 2.9: T = 48 D22 (1 - cos(alpha/2)) / (alpha^3 R) * (r_c / R) [N].

    Derived for an isotropic wall (D22 = D); the law flattens the section across its width,
    so a laminate's transverse rigidity D22 stands for D, a reading not checked against a
    laminate's wrapping.
    """
    return 48 * bending.D22 * (1 - math.cos(alpha / 2)) / (alpha**3 * R) * (r_c / R)


def required_coiling_tension(
    bending: Bending, alpha: float, R: float, r_hub: float, h: float
) -> tuple[float, str] | None:
    """The pull [N] a tape needs to wrap onto a hub of radius r_hub, with the law it comes from.

    The laws concern the first turn's mid-surface, rho = r_hub + h/2 (physics brief section 10);
    the regime is that of r_hub / R, as in :func:`coiling_regime`:

    - bending-dominated (r_hub/R <= 1): Eq. 2.6, (b / 2)(D11/rho^2 - D22/R^2), not below 0 (a
      mid-surface looser than R needs no pull by it); 0.374 N for the benchmark tape;
    - tension-dominated (r_hub/R >= 3.424): Eq. 2.9 with rho;
    - loss of uniqueness in between: None. No law gives the tension there: Eq. 2.6 is negative
      once rho > R, so as a lower estimate it bounds nothing, and Eq. 2.9 is derived for the
      tension-dominated regime only.
    """
    rho = r_hub + h / 2
    regime = coiling_regime(r_hub, R)
    if regime == "bending":
        return max(coiling_tension_bending(bending, alpha, R, rho), 0.0), "Eq. 2.6"
    if regime == "tension":
        return coiling_tension_tension_dominated(bending, alpha, R, rho), "Eq. 2.9"
    return None


def coiling_tension_growing(
    lam: float | np.ndarray, bending: Bending, alpha: float, R: float, r_hub: float, h: float, L: float
) -> dict[str, float | np.ndarray]:
    """Coiling tension with the coil radius r(lambda) (Eq. 4.5 and the corrected Eq. 4.6) [N].

    Returns both regimes' formulas evaluated at r(lambda): 'bending' is Eq. 4.5; 'tension' is
    Eq. 2.9 with r(lambda) (Eq. 4.6 as printed has a stray square root).
    """
    r = coil_radius_during_deployment(lam, r_hub, h, L)
    return {
        "radius": r,
        "bending": coiling_tension_bending(bending, alpha, R, r),
        "tension": coiling_tension_tension_dominated(bending, alpha, R, r),
    }
