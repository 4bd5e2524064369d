"""Finite rotations in 3D: the rotation matrix about an axis, and of rotation vectors."""

from __future__ import annotations

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
