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


# terms of the series of the Rodrigues coefficients in s = |theta|^2: entire functions, whose
# series converge for every s; enough terms for machine precision up to |theta| = 5 rad
_TERMS = 24
_LARGEST_ANGLE = 5.0


def _series(s: np.ndarray, first: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """sum_n (-s)^n / (2n + first)! and its first two derivatives in s, for arrays s."""
    value, d1, d2 = np.zeros_like(s), np.zeros_like(s), np.zeros_like(s)
    factorial = float(math.factorial(first))
    power = np.ones_like(s)  # s^n
    for n in range(_TERMS):
        if n > 0:
            factorial *= (2 * n + first - 1) * (2 * n + first)
        sign = -1.0 if n % 2 else 1.0
        value += sign * power / factorial
        if n >= 1:
            d1 += sign * n * s ** (n - 1) / factorial
        if n >= 2:
            d2 += sign * n * (n - 1) * s ** (n - 2) / factorial
        power = power * s
    return value, d1, d2


def _coefficients(theta: np.ndarray):
    s = np.einsum("ni,ni->n", theta, theta)
    if np.any(s > _LARGEST_ANGLE**2):
        raise ValueError(
            f"a rotation increment of {np.sqrt(s.max()):.3g} rad: beyond {_LARGEST_ANGLE:g} rad "
            "the step is not an increment"
        )
    return s, _series(s, 0), _series(s, 1), _series(s, 2)  # cos, sin a / a, (1 - cos a) / a^2


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
