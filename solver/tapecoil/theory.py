"""Analytic theory of tape-spring coiling and deployment (physics brief, thesis equations).

All functions take and return SI units. Equation numbers are the thesis's; where the thesis
is inconsistent the physics brief's consistent form is used and the docstring says so.

Sign convention for stresses: z is the distance from the mid-surface, positive on the face
away from the hub (the outer face of the coil). In opposite-sense coiling both the coil
curvature and the flattening of the cross-section stretch that face, so the outer face is in
tension in both directions and the inner face in compression.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from tapecoil.config import Config

# --- material and section ----------------------------------------------------------------


def flexural_rigidity(E: float, h: float, nu: float) -> float:
    """Plate flexural rigidity D = E h^3 / (12 (1 - nu^2)) [N m]."""
    return E * h**3 / (12 * (1 - nu**2))


def opposite_sense_energy_density(D: float, nu: float, R: float) -> float:
    """mu = D (1 + nu) / R^2 [J/m^2]: energy per unit area of the opposite-sense coil of radius R."""
    return D * (1 + nu) / R**2


def energy_density(rho: float | np.ndarray, R: float, D: float, nu: float) -> float | np.ndarray:
    """Kirchhoff plate energy per unit area of a flattened section coiled to radius rho [J/m^2].

    w(rho) = (D/2) (1/rho^2 + 1/R^2 + 2 nu / (rho R)); w(R) = mu (physics brief section 3).
    """
    return 0.5 * D * (1 / rho**2 + 1 / R**2 + 2 * nu / (rho * R))


def arc_second_moment(R: float, alpha: float, h: float) -> float:
    """Second moment of area of a thin circular-arc section about its centroidal axis [m^4].

    The axis is parallel to the chord (bending about the tape's width axis). Thin-wall form
    I = R^3 h (beta + sin(beta) cos(beta) - 2 sin(beta)^2 / beta), beta = alpha/2, plus the
    plate term b h^3 / 12 of the wall's own bending.
    """
    beta = alpha / 2
    s, c = math.sin(beta), math.cos(beta)
    return R**3 * h * (beta + s * c - 2 * s * s / beta) + R * alpha * h**3 / 12


def fold_moment(D: float, nu: float, alpha: float) -> float:
    """Steady moment of a localised opposite-sense fold, (1 + nu) D alpha [N m].

    Wuest (1954); Seffen and Pellegrino (1999). It is the moment plateau after the snap when a
    tape is bent so that its cross-section flattens.
    """
    return (1 + nu) * D * alpha


# --- coil geometry (section 2) -------------------------------------------------------------


def turn_radius(n: int | np.ndarray, r_hub: float, h: float) -> float | np.ndarray:
    """Mid-surface radius of turn n (n = 0 lies on the hub): r_hub + h/2 + n h [m]."""
    return r_hub + h / 2 + n * h


def outer_radius_after_rotation(theta: float, r_hub: float, h: float) -> float:
    """Coil radius after a hub rotation theta [rad]: r_hub + h theta / (2 pi) [m].

    Growth is h per turn; Eq. 2.26 as printed (2h per turn) contradicts the thesis's 13.27 mm.
    """
    return r_hub + h * theta / (2 * math.pi)


def coiled_length_from_radius(r: float, r_hub: float, h: float) -> float:
    """Eq. 4.3: coiled length x = (pi/h) (r^2 - r_hub^2) for a coil of outer radius r [m]."""
    return math.pi / h * (r**2 - r_hub**2)


def radius_from_coiled_length(x: float | np.ndarray, r_hub: float, h: float) -> float | np.ndarray:
    """Inverse of Eq. 4.3: r = sqrt(r_hub^2 + h x / pi) [m]."""
    return np.sqrt(r_hub**2 + h * np.asarray(x) / math.pi)


def coiled_length_from_rotation(theta: float, r_hub: float, h: float) -> float:
    """Length of tape wound by a hub rotation theta [m]: arc length of the mid-surface spiral.

    The mid-surface radius grows as r_hub + h/2 + h phi / (2 pi), so
    x = theta (r_hub + h/2) + h theta^2 / (4 pi). This is what is physically on the hub; Eq. 4.3
    with r = r_hub + h theta / (2 pi) gives a value 0.3 % lower for the benchmark.
    """
    return theta * (r_hub + h / 2) + h * theta**2 / (4 * math.pi)


def rotation_for_coiled_length(x: float, r_hub: float, h: float) -> float:
    """Hub rotation [rad] that winds a length x; inverse of :func:`coiled_length_from_rotation`."""
    a, b = h / (4 * math.pi), r_hub + h / 2
    return 2 * x / (b + math.sqrt(b * b + 4 * a * x))


def max_hub_angle(L: float, r_hub: float, h: float) -> float:
    """Largest hub rotation [rad] a tape of length L allows: the rotation that winds all of it.

    The mid-surface spiral of :func:`coiled_length_from_rotation` is what the model winds, so its
    inverse at x = L is where no free length is left to pull. Eq. 4.3 with the outer radius
    r_hub + h theta / (2 pi) puts the first turn on r_hub instead of r_hub + h/2 and allows
    0.4 % more: 38.44 rad against 38.30 rad for the benchmark tape (L = 0.5 m, r_hub = 12.7 mm).
    """
    return rotation_for_coiled_length(L, r_hub, h)


def stored_energy(theta: float, r_hub: float, h: float, R: float, alpha: float, D: float, nu: float) -> float:
    """Strain energy [J] of the flattened tape wound by a hub rotation theta (section 3).

    The plate estimate w(rho) integrated over the mid-surface spiral rho(phi) = r_hub + h/2 +
    h phi / (2 pi) with the arc width b = R alpha; the ploy (transition) region is not included.
    With ds = rho dphi and drho = h dphi / (2 pi) the integral is closed:
    U = b (2 pi / h) (D/2) [ln rho + rho^2 / (2 R^2) + 2 nu rho / R] from rho_0 to rho_theta.
    """
    b = R * alpha
    r0 = r_hub + h / 2
    r1 = r0 + h * theta / (2 * math.pi)

    def antiderivative(rho: float) -> float:
        return math.log(rho) + rho**2 / (2 * R**2) + 2 * nu * rho / R

    return b * (2 * math.pi / h) * 0.5 * D * (antiderivative(r1) - antiderivative(r0))


# --- stresses (section 4) ------------------------------------------------------------------


def coil_stresses(rho: float, R: float, E: float, nu: float, z: float) -> tuple[float, float]:
    """Plane-stress bending stresses (sigma_x, sigma_y) [Pa] at z in a coil of radius rho.

    Curvature changes +1/rho (longitudinal) and +1/R (transverse, flattening): eps_x = z/rho,
    eps_y = z/R. z > 0 on the outer face (see the module docstring); use z = +-h/2.
    """
    c = E / (1 - nu**2) * z
    return c * (1 / rho + nu / R), c * (1 / R + nu / rho)


# --- coiling tension (section 5) -----------------------------------------------------------

UNIQUENESS_LIMIT = 3.424
"""r_c/R above which coiling is tension-dominated; between 1 and this, loss of uniqueness."""


def coiling_regime(r_c: float, R: float) -> str:
    """'bending' (r_c/R <= 1), 'non-unique' (1 < r_c/R < 3.424) or 'tension' (>= 3.424)."""
    ratio = r_c / R
    if ratio <= 1:
        return "bending"
    return "non-unique" if ratio < UNIQUENESS_LIMIT else "tension"


def coiling_tension_bending(D: float, alpha: float, R: float, r_c: float) -> float:
    """Eq. 2.6: T = (D alpha / (2R)) ((R/r_c)^2 - 1) = (D b / 2)(1/r_c^2 - 1/R^2) [N].

    The configurational-force balance T = M kappa - U of a flattened coil of radius r_c.
    """
    return D * alpha / (2 * R) * ((R / r_c) ** 2 - 1)


def coiling_tension_tension_dominated(D: float, alpha: float, R: float, r_c: float) -> float:
    """Eq. 2.9: T = 48 D (1 - cos(alpha/2)) / (alpha^3 R) * (r_c / R) [N]."""
    return 48 * D * (1 - math.cos(alpha / 2)) / (alpha**3 * R) * (r_c / R)


def required_coiling_tension(
    D: float, alpha: float, R: float, r_hub: float, h: float
) -> tuple[float, str] | None:
    """The pull [N] a tape needs to wrap onto a hub of radius r_hub, with the law it comes from.

    The laws concern the first turn's mid-surface, rho = r_hub + h/2 (physics brief section 10);
    the regime is that of r_hub / R, as in :func:`coiling_regime`:

    - bending-dominated (r_hub/R <= 1): Eq. 2.6, (D b / 2)(1/rho^2 - 1/R^2), not below 0 (a
      mid-surface looser than R needs no pull by it); 0.374 N for the benchmark tape;
    - tension-dominated (r_hub/R >= 3.424): Eq. 2.9 with rho;
    - loss of uniqueness in between: None. No law gives the tension there: Eq. 2.6 is negative
      once rho > R, so as a lower estimate it bounds nothing, and Eq. 2.9 is derived for the
      tension-dominated regime only.
    """
    rho = r_hub + h / 2
    regime = coiling_regime(r_hub, R)
    if regime == "bending":
        return max(coiling_tension_bending(D, alpha, R, rho), 0.0), "Eq. 2.6"
    if regime == "tension":
        return coiling_tension_tension_dominated(D, alpha, R, rho), "Eq. 2.9"
    return None


def coil_radius_during_deployment(lam: float | np.ndarray, r_hub: float, h: float, L: float):
    """r(lambda) = sqrt(r_hub^2 + h (1 - lambda) L / pi) [m]: Eq. 4.3 with x = (1 - lambda) L."""
    return radius_from_coiled_length((1 - np.asarray(lam)) * L, r_hub, h)


def coiling_tension_growing(
    lam: float | np.ndarray, D: float, alpha: float, R: float, r_hub: float, h: float, L: float
) -> dict[str, float | np.ndarray]:
    """Coiling tension with the coil radius r(lambda) (Eq. 4.5 and the corrected Eq. 4.6) [N].

    Returns both regimes' formulas evaluated at r(lambda): 'bending' is Eq. 4.5; 'tension' is
    Eq. 2.9 with r(lambda) (Eq. 4.6 as printed has a stray square root).
    """
    r = coil_radius_during_deployment(lam, r_hub, h, L)
    return {
        "radius": r,
        "bending": D * alpha / (2 * R) * ((R / r) ** 2 - 1),
        "tension": 48 * D * (1 - math.cos(alpha / 2)) / (alpha**3 * R) * (r / R),
    }


# --- deployment (section 6) ----------------------------------------------------------------


def seffen_rate(mu: float, r: float, R: float, alpha: float, rho_l: float, L: float) -> float:
    """k = sqrt(6 mu r^2 R alpha / (rho_l L^4)) [1/s], the rate in lambda dlambda = k dt (Eq. 2.21)."""
    return math.sqrt(6 * mu * r**2 * R * alpha / (rho_l * L**4))


def deployed_fraction(t: float | np.ndarray, k: float) -> float | np.ndarray:
    """Eq. 2.20: lambda(t) = sqrt(2 k t), capped at 1 (full deployment)."""
    return np.minimum(np.sqrt(2 * k * np.asarray(t, dtype=float)), 1.0)


def deployment_time(k: float, lam: float = 1.0) -> float:
    """Eq. 2.23 (lam = 1): time to reach the deployed fraction lam from lambda = 0, lam^2/(2k) [s]."""
    return lam**2 / (2 * k)


def deployment_time_lambda0(k: float, lam0: float, lam: float = 1.0) -> float:
    """Eq. 2.25: time to reach lam from an initial unspooled fraction lam0 (constant radius) [s].

    Closed-form integral of Eq. 2.24, lambda' = k sqrt((lambda - lambda0) / lambda^3).
    """
    if lam0 == 0:
        return deployment_time(k, lam)
    root = math.sqrt(lam * (lam - lam0))
    lhs = (lam / 2 + 3 * lam0 / 4) * root + 3 * lam0**2 / 8 * (
        math.log(abs(lam - lam0 / 2 + root)) - math.log(lam0 / 2)
    )
    return lhs / k


@dataclass
class DeploymentSolution:
    """lambda(t) from the modified ODE, with the times to 90 % and 100 % deployment.

    Internally t(s), s = sqrt(lambda - lambda0), is the ODE's dense output; lambda(t) inverts
    it by Newton's method on that interpolant, so both directions keep the ODE's accuracy.
    """

    t: np.ndarray
    lam: np.ndarray
    lam0: float
    t90: float
    t100: float
    _t_of_s: Callable[[np.ndarray], np.ndarray]
    _dt_ds: Callable[[np.ndarray], np.ndarray]

    def time_to(self, lam: float | np.ndarray) -> float | np.ndarray:
        """Time [s] to reach the deployed fraction lam (lambda0 <= lam <= 1)."""
        s = np.sqrt(np.clip(np.asarray(lam, dtype=float) - self.lam0, 0.0, 1.0 - self.lam0))
        t = self._t_of_s(s)
        return float(t) if np.ndim(lam) == 0 else t

    def __call__(self, t: float | np.ndarray) -> float | np.ndarray:
        """Deployed fraction lambda at time(s) t [s]; 1 after full deployment."""
        tq = np.clip(np.asarray(t, dtype=float), 0.0, self.t100)
        s_grid = np.sqrt(self.lam - self.lam0)
        s = np.interp(tq, self.t, s_grid)
        for _ in range(8):
            slope = self._dt_ds(s)
            step = np.where(slope > 0, (self._t_of_s(s) - tq) / np.where(slope > 0, slope, 1.0), 0.0)
            s = np.clip(s - step, 0.0, s_grid[-1])
        lam = self.lam0 + s * s
        return float(lam) if np.ndim(t) == 0 else lam


def solve_deployment_ode(
    rate: Callable[[float], float], lam0: float = 0.0, rtol: float = 1e-11, samples: int = 401
) -> DeploymentSolution:
    """Integrate lambda' = k(lambda) sqrt((lambda - lambda0)/lambda^3) from lambda0 to 1 with scipy.

    ``rate`` is k(lambda) [1/s]: constant for Eq. 2.20/2.25, or seffen_rate with r(lambda) for
    the modified Eq. 4.4 (the thesis's Eq. 4.4 is this with lambda0 = 0; the sqrt factor is
    Eq. 2.24's). The equation starts from rest at lambda0 > 0 and is singular at lambda = 0 for
    lambda0 = 0, so it is integrated as t(s) with s = sqrt(lambda - lambda0), where
    dt/ds = 2 lambda^(3/2) / k(lambda) is regular for every lambda0 >= 0.
    """
    if not 0 <= lam0 < 1:
        raise ValueError(f"lam0 must be in [0, 1), got {lam0}")

    def dt_ds(s):
        lam = lam0 + np.asarray(s) ** 2
        return 2 * lam**1.5 / np.vectorize(rate, otypes=[float])(lam)

    s_end = math.sqrt(1 - lam0)
    sol = solve_ivp(
        lambda s, _t: [float(dt_ds(s))],
        (0.0, s_end),
        [0.0],
        dense_output=True,
        rtol=rtol,
        atol=1e-14,
        method="DOP853",
    )
    if not sol.success:  # pragma: no cover - smooth integrand
        raise RuntimeError(f"deployment ODE failed: {sol.message}")

    def t_of_s(s):
        return sol.sol(np.asarray(s))[0]

    s = np.linspace(0.0, s_end, samples)
    t90 = float(t_of_s(math.sqrt(0.9 - lam0))) if lam0 < 0.9 else 0.0
    return DeploymentSolution(
        t=t_of_s(s),
        lam=lam0 + s * s,
        lam0=lam0,
        t90=t90,
        t100=float(sol.y[0, -1]),
        _t_of_s=t_of_s,
        _dt_ds=dt_ds,
    )


# --- ploy region (section 7) -----------------------------------------------------------------


def ploy_length(width: float, R: float, h: float, beta: float = 1.0) -> float:
    """Eq. 3.5, dimensionally consistent reading: L_p = w^2 / (sqrt(70) beta^(1/4) sqrt(R h)) [m].

    As printed (R^2 t^(1/2) in the denominator) the formula is not a length. beta = 1 for an
    isotropic tape. The prefactor is uncertain: evaluate it for both the arc width and the
    projected width and compare with the measured transition length.
    """
    return width**2 / (math.sqrt(70) * beta**0.25 * math.sqrt(R * h))


# --- all predictions for a configuration -------------------------------------------------------


@dataclass(frozen=True)
class Prediction:
    """One analytic prediction: a key for JSON, a label, the value, its unit and its source."""

    key: str
    label: str
    value: float
    unit: str
    source: str


def predictions(config: Config) -> list[Prediction]:
    """Every analytic prediction of the physics brief for a configuration, in report order."""
    tp, r_hub = config.tape, config.hub.radius
    theta = config.coiling.hub_angle
    D, mu, b = tp.D, tp.mu, tp.b
    r_final = outer_radius_after_rotation(theta, r_hub, tp.h)
    x_coiled = min(coiled_length_from_rotation(theta, r_hub, tp.h), tp.L)
    theta_coiled = rotation_for_coiled_length(x_coiled, r_hub, tp.h)
    rho_first = turn_radius(0, r_hub, tp.h)
    sx, sy = coil_stresses(r_hub, tp.R, tp.E, tp.nu, tp.h / 2)
    k_hub = seffen_rate(mu, r_hub, tp.R, tp.alpha, tp.rho_l, tp.L)
    k_coil = seffen_rate(mu, r_final, tp.R, tp.alpha, tp.rho_l, tp.L)

    def k_growing(lam):
        r = coil_radius_during_deployment(lam, r_hub, tp.h, tp.L)
        return seffen_rate(mu, r, tp.R, tp.alpha, tp.rho_l, tp.L)

    ode = solve_deployment_ode(k_growing, 0.0)
    regime = coiling_regime(r_hub, tp.R)
    P = Prediction
    out = [
        P("D", "flexural rigidity D", D, "N m", "E h^3 / (12 (1 - nu^2))"),
        P("mu", "energy density of an opposite-sense coil, mu", mu, "J/m^2", "D (1 + nu) / R^2"),
        P("b", "arc width b", b, "m", "R alpha"),
        P("density", "volume density", tp.density, "kg/m^3", "rho_l / (b h)"),
        P(
            "I_arc",
            "second moment of the arc section",
            arc_second_moment(tp.R, tp.alpha, tp.h),
            "m^4",
            "thin arc",
        ),
        P(
            "fold_moment",
            "fold moment plateau (1 + nu) D alpha",
            fold_moment(D, tp.nu, tp.alpha),
            "N m",
            "Wuest 1954",
        ),
        P("coil_radius", f"coil radius after {theta:g} rad", r_final, "m", "r_hub + h theta / (2 pi)"),
        P("turns", "turns on the hub", theta_coiled / (2 * math.pi), "-", "theta / (2 pi)"),
        P("coiled_length", f"length coiled by {theta:g} rad", x_coiled, "m", "mid-surface spiral"),
        P(
            "coiled_length_eq43",
            "coiled length, Eq. 4.3 with the coil radius",
            min(coiled_length_from_radius(r_final, r_hub, tp.h), tp.L),
            "m",
            "Eq. 4.3",
        ),
        P(
            "w_first_turn",
            "energy density of the first turn w(r_hub + h/2)",
            energy_density(rho_first, tp.R, D, tp.nu),
            "J/m^2",
            "section 3",
        ),
        P(
            "stored_energy",
            "stored strain energy of the coiled length",
            stored_energy(theta_coiled, r_hub, tp.h, tp.R, tp.alpha, D, tp.nu),
            "J",
            "section 3",
        ),
        P("sigma_x", "surface stress sigma_x at rho = r_hub, z = h/2", sx, "Pa", "section 4"),
        P("sigma_y", "surface stress sigma_y at rho = r_hub, z = h/2", sy, "Pa", "section 4"),
        P(
            "coiling_ratio",
            f"coiling ratio r_hub / R ({regime}-dominated)"
            if regime != "non-unique"
            else "coiling ratio r_hub / R (non-unique regime)",
            r_hub / tp.R,
            "-",
            "section 5",
        ),
    ]
    # in the non-unique regime (1 < r_c/R < 3.424) neither law applies
    tension_laws = {
        "bending": (coiling_tension_bending, "Eq. 2.6"),
        "tension": (coiling_tension_tension_dominated, "Eq. 2.9"),
    }
    if regime in tension_laws:
        law, source = tension_laws[regime]
        out.append(P("coiling_tension", "coiling tension", law(D, tp.alpha, tp.R, r_hub), "N", source))
    out += [
        P("T_deploy_hub", "deployment time, r = r_hub", deployment_time(k_hub), "s", "Eq. 2.23"),
        P("t90_hub", "time to lambda = 0.9, r = r_hub", deployment_time(k_hub, 0.9), "s", "Eq. 2.20"),
        P("T_deploy_coil", "deployment time, r = coil radius", deployment_time(k_coil), "s", "Eq. 2.23"),
        P("T_deploy_ode", "deployment time, growing radius", ode.t100, "s", "Eq. 4.4"),
        P("t90_ode", "time to lambda = 0.9, growing radius", ode.t90, "s", "Eq. 4.4"),
        P(
            "ploy_length_arc",
            "ploy length, arc width",
            ploy_length(b, tp.R, tp.h),
            "m",
            "Eq. 3.5 (consistent)",
        ),
        P(
            "ploy_length_projected",
            "ploy length, projected width",
            ploy_length(tp.projected_width, tp.R, tp.h),
            "m",
            "Eq. 3.5 (consistent)",
        ),
    ]
    return out
