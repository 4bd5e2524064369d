"""Deployment of a coiled tape: Seffen and Pellegrino's ODE and its closed forms (physics brief section 6)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp


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
