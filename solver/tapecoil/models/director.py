"""The director map of the Naghdi shell: d(theta) in a director frame, its frames, its inverse.

The map and the two frames ("local", "global") are those of :mod:`tapecoil.models.shell`'s
docstring. UFL for the forms (the map, its secant derivative over a step, the frame of a
reference surface), numpy for setting states (the angles of given directors).
"""

from __future__ import annotations

import numpy as np
import ufl

FRAMES = ("local", "global")


def director_from_angles(theta, frame):
    """Director d(theta) in the frame (e1, e2, e3), see the module docstring."""
    t1, t2, n0 = frame
    c0, s0 = ufl.cos(theta[0]), ufl.sin(theta[0])
    return c0 * ufl.sin(theta[1]) * t1 - s0 * t2 + c0 * ufl.cos(theta[1]) * n0


def reference_frame(J0, n0, kind: str):
    """The director frame (e1, e2, e3) ``kind`` of a surface with covariant basis J0 and unit
    normal n0, and the reference angles theta_ref of n0 in it (UFL)."""
    if kind == "local":
        t1 = J0[:, 0] / ufl.sqrt(ufl.dot(J0[:, 0], J0[:, 0]))
        return (t1, ufl.cross(n0, t1), n0), ufl.as_vector([0.0, 0.0])
    frame = tuple(ufl.as_vector(e) for e in np.eye(3))
    return frame, ufl.as_vector([-ufl.asin(n0[1]), ufl.atan2(n0[0], n0[2])])


def angles_from_director(d: np.ndarray, frame: tuple[np.ndarray, ...], theta1_near: np.ndarray | float = 0.0):
    """Angles (theta_0, theta_1) of unit directors d (3, n) in frames (3, n) each; numpy.

    theta_1 is defined up to multiples of 2 pi: the branch nearest ``theta1_near`` is returned,
    so that rotations through several turns stay continuous.
    """
    t1, t2, n0 = frame
    dt1, dt2, dn = (np.einsum("in,in->n", d, v) for v in (t1, t2, n0))
    theta0 = -np.arcsin(np.clip(dt2, -1.0, 1.0))
    theta1 = np.arctan2(dt1, dn)
    theta1 = theta1 + 2 * np.pi * np.round((theta1_near - theta1) / (2 * np.pi))
    return np.vstack([theta0, theta1])


def director_secant(theta0, theta1, frame):
    """A 3 x 2 discrete derivative of the director map between the total angles theta0 and theta1.

    Dd_bar (theta1 - theta0) = d(theta1) - d(theta0) holds exactly (Gonzalez's discrete
    gradient, applied to each component of d): the derivative at the midpoint plus a correction
    along the step, which is of second order in the step. Steps below 1e-12 rad take the
    midpoint derivative alone.
    """
    mid = ufl.variable(0.5 * (theta0 + theta1))
    derivative = ufl.diff(director_from_angles(mid, frame), mid)
    step = theta1 - theta0
    length2 = ufl.dot(step, step)
    rest = (
        director_from_angles(theta1, frame) - director_from_angles(theta0, frame) - ufl.dot(derivative, step)
    )
    eps = 1e-24
    weight = ufl.conditional(ufl.gt(length2, eps), 1.0 / ufl.max_value(length2, eps), 0.0)
    return derivative + weight * ufl.outer(rest, step)
