"""Finite rotations in 3D: the rotation matrix about an axis, and of rotation vectors."""

from __future__ import annotations

import math

import numpy as np


def rotation_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` [rad] about the unit vector ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def rotation_matrices(vectors: np.ndarray) -> np.ndarray:
    """The rotations (n, 3, 3) by the rotation vectors ``vectors`` (n, 3) [rad] (Rodrigues;
    exact at zero)."""
    v = np.asarray(vectors, dtype=float).reshape(-1, 3)
    angle = np.linalg.norm(v, axis=1)
    small = angle < 1e-8
    safe = np.where(small, 1.0, angle)
    f1 = np.where(small, 1.0 - angle**2 / 6, np.sin(angle) / safe)
    f2 = np.where(small, 0.5 - angle**2 / 24, (1 - np.cos(angle)) / safe**2)
    K = np.zeros((len(v), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    return np.eye(3) + f1[:, None, None] * K + f2[:, None, None] * K @ K


# below this s = |theta|^2 the Rodrigues coefficients come from their series in s (entire
# functions: enough terms for machine precision up to s = 1), above it in closed form (which
# would cancel as s -> 0)
_TERMS = 16
_SERIES_BELOW = 1.0


def _series(s: np.ndarray, first: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """sum_n (-s)^n / (2n + first)! and its first two derivatives in s, for arrays s."""
    value, d1, d2 = np.zeros_like(s), np.zeros_like(s), np.zeros_like(s)
    factorial = float(math.factorial(first))
    for n in range(_TERMS):
        if n > 0:
            factorial *= (2 * n + first - 1) * (2 * n + first)
        sign = -1.0 if n % 2 else 1.0
        value += sign * s**n / factorial
        if n >= 1:
            d1 += sign * n * s ** (n - 1) / factorial
        if n >= 2:
            d2 += sign * n * (n - 1) * s ** (n - 2) / factorial
    return value, d1, d2


def _closed(s: np.ndarray):
    """cos a, sin a / a, (1 - cos a) / a^2 (a^2 = s > 0) and their first two derivatives in s."""
    a = np.sqrt(s)
    gam, alp = np.cos(a), np.sin(a) / a
    bet = (1.0 - gam) / s
    gam1, alp1 = -alp / 2, (gam - alp) / (2 * s)
    bet1 = (alp - 2 * bet) / (2 * s)
    gam2 = -alp1 / 2
    alp2 = (gam1 - alp1) / (2 * s) - alp1 / s
    bet2 = (alp1 - 2 * bet1) / (2 * s) - bet1 / s
    return (gam, gam1, gam2), (alp, alp1, alp2), (bet, bet1, bet2)


def _coefficients(theta: np.ndarray):
    """s = |theta|^2 and the Rodrigues coefficients cos a, sin a / a, (1 - cos a) / a^2 with
    their first two derivatives in s, each a triple of arrays."""
    s = np.einsum("ni,ni->n", theta, theta)
    small = s < _SERIES_BELOW
    series = [_series(np.where(small, s, 0.0), first) for first in (0, 1, 2)]
    closed = _closed(np.where(small, 1.0, s))
    out = tuple(
        tuple(np.where(small, x, y) for x, y in zip(sx, cx, strict=True))
        for sx, cx in zip(series, closed, strict=True)
    )
    return (s, *out)


def rotated(theta: np.ndarray, w: np.ndarray) -> np.ndarray:
    """R(theta) w (n, 3) for rotation vectors ``theta`` (n, 3) and vectors ``w`` (n, 3)
    (Rodrigues: R w = cos(a) w + sin(a)/a theta x w + (1 - cos a)/a^2 (theta . w) theta)."""
    _, (g, _, _), (a, _, _), (b, _, _) = _coefficients(theta)
    c = np.einsum("ni,ni->n", theta, w)
    return g[:, None] * w + a[:, None] * np.cross(theta, w) + (b * c)[:, None] * theta


def rotated_derivative(theta: np.ndarray, w: np.ndarray) -> np.ndarray:
    """d(R(theta) w)/dtheta (n, 3, 3): [k, i, j] = d(R w)_i / dtheta_j."""
    _, (_, g1, _), (a, a1, _), (b, b1, _) = _coefficients(theta)
    c = np.einsum("ni,ni->n", theta, w)
    u = np.cross(theta, w)
    v = g1[:, None] * w + a1[:, None] * u + (b1 * c)[:, None] * theta
    W = np.zeros((len(w), 3, 3))  # [w]_x
    W[:, 0, 1], W[:, 0, 2], W[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    W[:, 1, 0], W[:, 2, 0], W[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    return (
        2.0 * v[:, :, None] * theta[:, None, :]
        - a[:, None, None] * W
        + b[:, None, None] * (theta[:, :, None] * w[:, None, :] + c[:, None, None] * np.eye(3))
    )


def rotated_second_derivative(theta: np.ndarray, w: np.ndarray, g_vec: np.ndarray) -> np.ndarray:
    """sum_i g_i d2(R(theta) w)_i / dtheta_j dtheta_k (n, 3, 3), symmetric: the second derivative
    of R(theta) w contracted with vectors ``g_vec`` (n, 3) (a force on the rotated point)."""
    _, (_, gam1, gam2), (_, a1, a2), (b, b1, b2) = _coefficients(theta)
    c = np.einsum("ni,ni->n", theta, w)
    u = np.cross(theta, w)
    g = g_vec
    gw, gu, gt = (np.einsum("ni,ni->n", g, x) for x in (w, u, theta))
    v = gam1[:, None] * w + a1[:, None] * u + (b1 * c)[:, None] * theta
    gv = np.einsum("ni,ni->n", g, v)
    wxg = np.cross(w, g)
    q = (
        2.0 * theta * (gam2 * gw + a2 * gu + b2 * c * gt)[:, None]
        + a1[:, None] * wxg
        + b1[:, None] * (w * gt[:, None] + c[:, None] * g)
    )
    p = a1[:, None] * wxg + b1[:, None] * (gt[:, None] * w + c[:, None] * g)
    S = 2.0 * theta[:, :, None] * q[:, None, :]
    S += 2.0 * p[:, :, None] * theta[:, None, :]
    S += 2.0 * gv[:, None, None] * np.eye(3)
    S += b[:, None, None] * (w[:, :, None] * g[:, None, :] + g[:, :, None] * w[:, None, :])
    return S
