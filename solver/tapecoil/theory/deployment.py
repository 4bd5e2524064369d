"""Deployment of a coiled tape: Seffen and Pellegrino's ODE and its closed forms (physics brief section 6)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from tapecoil.theory.coil_geometry import radius_from_coiled_length


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


def coil_rotary_inertia(lam: float, r: float, r_hub: float, rho_l: float, L: float) -> float:
    """Rotary inertia about the hub's axis of the tape turning with the hub [kg m^2].

    The coiled part, (1 - lam) L of a spiral from r_hub to r (its mass per unit radius grows
    as the radius: mean square radius (r_hub^2 + r^2)/2), and the deployed part, which the
    turning hub pays out along its own line at the speed r zeta' of the tangent point.
    At lam = 0 it is the stowed tape's own rotary inertia on the coil.
    """
    return rho_l * L * ((1 - lam) * (r_hub**2 + r**2) / 2 + lam * r**2)


def stowed_rotary_inertia(r_hub: float, h: float, L: float, rho_l: float) -> float:
    """The stowed tape's own rotary inertia on the coil [kg m^2]: the whole length L wound from
    r_hub to the radius r(0) of Eq. 4.3, rho_l L (r_hub^2 + r(0)^2) / 2
    (:func:`coil_rotary_inertia` at lambda = 0)."""
    r0 = float(radius_from_coiled_length(L, r_hub, h))
    return coil_rotary_inertia(0.0, r0, r_hub, rho_l, L)


def free_hub_factors(lam: float, r: float, hub_inertia: float, rho_l: float, L: float) -> tuple[float, float]:
    """The free hub's effect at the deployed fraction lam: (rate factor, hub turn per lambda).

    Seffen and Pellegrino's free-drum model (thesis Eq. 2.17, with the drum's own equation): the
    drum of rotary inertia I_h (``hub_inertia``: the hub's J plus :func:`coil_rotary_inertia`)
    turns by zeta, the straight part of length lam L, tangent to the coil of radius r, turns by
    phi = theta + zeta and has the rotary inertia I_s = rho_l (lam L)^3 / 3 about the tangent
    point. From rest, nothing outside turns the two: the angular momentum
    I_h zeta' + I_s phi' stays 0, so zeta' = -I_s theta' / (I_h + I_s), and the kinetic energy is
    (theta'^2 / 2) I_h I_s / (I_h + I_s) instead of the fixed drum's (theta'^2 / 2) I_s. The
    energy balance then gives the fixed hub's lambda' times sqrt(1 + I_s / I_h), and the hub
    turns back by dzeta/dlambda = -(I_s / (I_h + I_s)) L / r (rad per unit lambda, in the
    coiling sense). The thesis prints Eq. 2.17 with zeta'^2 + theta'^2 where its own Eq. 2.18
    (zeta = 0) needs theta'^2 with the minus sign; the derivation here reduces to Eq. 2.18.
    """
    inertia_straight = rho_l * (lam * L) ** 3 / 3
    factor = math.sqrt(1 + inertia_straight / hub_inertia) if hub_inertia > 0 else math.inf
    turn = -inertia_straight / (hub_inertia + inertia_straight) * L / r
    return factor, turn


@dataclass
class DeploymentSolution:
    """lambda(t) from the modified ODE, with the times to 90 % and 100 % deployment.

    Internally t(s), s = sqrt(lambda - lambda0), is the ODE's dense output; lambda(t) inverts
    it by Newton's method on that interpolant, so both directions keep the ODE's accuracy. For
    a free hub the hub's turn since release, integrated along, is :meth:`hub_turn`.
    """

    t: np.ndarray
    lam: np.ndarray
    lam0: float
    t90: float
    t100: float
    _t_of_s: Callable[[np.ndarray], np.ndarray]
    _dt_ds: Callable[[np.ndarray], np.ndarray]
    _turn_of_s: Callable[[np.ndarray], np.ndarray] | None = None

    def _s(self, lam):
        return np.sqrt(np.clip(np.asarray(lam, dtype=float) - self.lam0, 0.0, 1.0 - self.lam0))

    def time_to(self, lam: float | np.ndarray) -> float | np.ndarray:
        """Time [s] to reach the deployed fraction lam (lambda0 <= lam <= 1)."""
        t = self._t_of_s(self._s(lam))
        return float(t) if np.ndim(lam) == 0 else t

    def hub_turn(self, lam: float | np.ndarray) -> float | np.ndarray:
        """The hub's turn [rad] (coiling sense) from release to the deployed fraction lam."""
        if self._turn_of_s is None:
            raise ValueError("this solution is of a fixed hub: it has no hub turn")
        turn = self._turn_of_s(self._s(lam))
        return float(turn) if np.ndim(lam) == 0 else turn

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
    rate: Callable[[float], float],
    lam0: float = 0.0,
    rtol: float = 1e-11,
    samples: int = 401,
    hub_turn: Callable[[float], float] | None = None,
) -> DeploymentSolution:
    """Integrate lambda' = k(lambda) sqrt((lambda - lambda0)/lambda^3) from lambda0 to 1 with scipy.

    ``rate`` is k(lambda) [1/s]: constant for Eq. 2.20/2.25, or seffen_rate with r(lambda) for
    the modified Eq. 4.4 (the thesis's Eq. 4.4 is this with lambda0 = 0; the sqrt factor is
    Eq. 2.24's), times the factor of :func:`free_hub_factors` for a free hub, whose turn per
    unit lambda is then ``hub_turn`` (integrated along). The equation starts from rest at
    lambda0 > 0 and is singular at lambda = 0 for lambda0 = 0, so it is integrated as t(s) with
    s = sqrt(lambda - lambda0), where dt/ds = 2 lambda^(3/2) / k(lambda) is regular for every
    lambda0 >= 0.
    """
    if not 0 <= lam0 < 1:
        raise ValueError(f"lam0 must be in [0, 1), got {lam0}")

    def dt_ds(s):
        lam = lam0 + np.asarray(s) ** 2
        return 2 * lam**1.5 / np.vectorize(rate, otypes=[float])(lam)

    def derivatives(s, _y):
        rates = [float(dt_ds(s))]
        if hub_turn is not None:
            rates.append(2 * s * hub_turn(lam0 + s * s))
        return rates

    s_end = math.sqrt(1 - lam0)
    sol = solve_ivp(
        derivatives,
        (0.0, s_end),
        [0.0] if hub_turn is None else [0.0, 0.0],
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
        _turn_of_s=None if hub_turn is None else (lambda s: sol.sol(np.asarray(s))[1]),
    )
