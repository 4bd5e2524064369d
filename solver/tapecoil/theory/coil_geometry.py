"""The coil as a spiral: turn radii, coiled length against hub rotation, stored energy.

Physics brief sections 2 and 3 and the thesis's Eq. 4.3; SI units.
"""

from __future__ import annotations

import math

import numpy as np

from tapecoil.theory.laminate import Bending
from tapecoil.theory.plate import sense_sign


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


def stored_energy(
    theta: float, r_hub: float, h: float, R: float, alpha: float, bending: Bending, sense: str = "opposite"
) -> float:
    """Strain energy [J] of the flattened tape wound by a hub rotation theta (section 3).

    The plate estimate w(rho) of the coiling ``sense`` (:func:`~tapecoil.theory.plate.energy_density`)
    integrated over the mid-surface spiral rho(phi) = r_hub + h/2 + h phi / (2 pi) with the arc
    width b = R alpha; the ploy (transition) region is not included. With ds = rho dphi and
    drho = h dphi / (2 pi) the integral is closed: U = b (2 pi / h) (1/2) [D11 ln rho +
    D22 rho^2 / (2 R^2) +- 2 D12 rho / R] from rho_0 to rho_theta (+ opposite, - equal sense).
    """
    b = R * alpha
    r0 = r_hub + h / 2
    r1 = r0 + h * theta / (2 * math.pi)
    s = sense_sign(sense)
    d = bending

    def antiderivative(rho: float) -> float:
        return d.D11 * math.log(rho) + d.D22 * rho**2 / (2 * R**2) + s * 2 * d.D12 * rho / R

    return b * (2 * math.pi / h) * 0.5 * (antiderivative(r1) - antiderivative(r0))


def coil_radius_during_deployment(lam: float | np.ndarray, r_hub: float, h: float, L: float):
    """r(lambda) = sqrt(r_hub^2 + h (1 - lambda) L / pi) [m]: Eq. 4.3 with x = (1 - lambda) L."""
    return radius_from_coiled_length((1 - np.asarray(lam)) * L, r_hub, h)
