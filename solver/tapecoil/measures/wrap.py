"""How closely a tape wrapped round a cylinder follows it: the conforming wrap and the folds.

Read from the centre line alone (its winding angle psi about the hub axis and its mid-surface
distance r from the axis, :func:`tapecoil.measures.centre_line.centre_line`), independently of
the contact that holds the tape on the hub. Wilson et al. (2020) count a tape as wrapped when
its centre line lies within three thicknesses of the cylinder over a wrap of 305 to 315 degrees
(physics brief Sec. 10).
"""

from __future__ import annotations

import math

import numpy as np


def menger_curvature(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Curvature of the circle through each point and its two neighbours (0 at the two ends) [1/m]."""
    kappa = np.zeros_like(x)
    if x.size < 3:
        return kappa
    ax, ay = x[:-2] - x[1:-1], y[:-2] - y[1:-1]
    bx, by = x[2:] - x[1:-1], y[2:] - y[1:-1]
    cross = ax * by - ay * bx
    a, b = np.hypot(ax, ay), np.hypot(bx, by)
    c = np.hypot(x[2:] - x[:-2], y[2:] - y[:-2])
    kappa[1:-1] = 2 * np.abs(cross) / np.maximum(a * b * c, 1e-300)
    return kappa


def wrap_measure(
    psi: np.ndarray,
    radius: np.ndarray,
    surface_radius: float,
    h: float,
    wrap_angle: float,
    tolerance: float = 3.0,
    xi1: np.ndarray | None = None,
    edges: tuple[tuple[np.ndarray, np.ndarray], ...] = (),
    fold_margin: float = 0.05,
) -> dict:
    """The conforming wrap and the folds of a centre line wrapped from psi = 0 (the attached end).

    ``psi``, ``radius``: the centre line's winding angle [rad] and distance from the hub axis
    [m], sorted along the tape. ``surface_radius``: the mid-surface radius of a tape lying on
    the cylinder, r_c + h/2 [m]. ``wrap_angle``: the hub angle the tape was wrapped by [rad]
    (where it leaves the hub). ``tolerance``: the conformity band, in thicknesses ``h``.

    Returns:
        conforming_wrap: the largest angle [rad] up to which every centre-line point from the
            attached end lies within ``tolerance`` h of the cylinder.
        folds: the number of stretches of the centre line off the cylinder with the cylinder
            regained on both sides (the stretch that runs into the free part is the lift-off,
            not a fold) and bent somewhere more tightly than the cylinder, its radius of
            curvature below (1 - ``fold_margin``) ``surface_radius``. A smooth stretch lifted a
            few h bends about as the cylinder does (within 2 % for 10 h over 200 degrees on a
            50 mm cylinder): it stands loose, as a coil on a hub smaller than R does when the
            pull drops, and is not a fold. The folds of the tension-dominated and
            non-unique regimes are of radius between R and r_c, well inside the margin.
        fold_radii: for each fold, the smallest radius of curvature of the centre line in it
            [m] (circles through neighbouring nodes of the curve in the plane of the wrap).
        fold_angles: for each fold, the winding angle of its highest point [rad].
        largest_gap: the largest distance of the centre line from the cylinder within the wrap [m].
        section_rise: the largest height of an edge above the centre line (distance from the
            axis, edge minus centre) over the conforming wrap [m]: about 0 where the section
            lies flattened on the cylinder, R (1 - cos(alpha/2)) where it keeps its arc.
    """
    wrapped = psi < wrap_angle
    gap = radius - surface_radius
    off = np.abs(gap) > tolerance * h
    inside = off & wrapped
    conforming = float(psi[inside].min()) if inside.any() else float(min(wrap_angle, psi.max()))
    x, y = radius * np.cos(psi), radius * np.sin(psi)
    kappa = menger_curvature(x, y)
    # runs of off points within the wrap, each bounded by conforming points on both sides
    flags = np.concatenate([[0], inside.astype(int), [0]])
    starts, ends = np.flatnonzero(np.diff(flags) == 1), np.flatnonzero(np.diff(flags) == -1)
    radii, angles = [], []
    for a, b in zip(starts, ends, strict=True):
        if a == 0 or b >= psi.size or not wrapped[b] or off[b]:
            continue
        stretch = slice(a, b)
        tightest = float(1.0 / max(kappa[stretch].max(), 1e-300))
        if tightest >= (1 - fold_margin) * surface_radius:
            continue  # a loose stretch, not a fold
        radii.append(tightest)
        angles.append(float(psi[stretch][np.argmax(gap[stretch])]))
    rise = 0.0
    if xi1 is not None:
        on = psi < conforming
        for edge_xi1, edge_radius in edges:
            if on.any() and edge_xi1.size:
                rise = max(rise, float(np.max(np.interp(xi1[on], edge_xi1, edge_radius) - radius[on])))
    return {
        "conforming_wrap": conforming,
        "conforming_wrap_deg": math.degrees(conforming),
        "folds": len(radii),
        "fold_radii": radii,
        "fold_angles": angles,
        "largest_gap": float(np.abs(gap[wrapped]).max()) if wrapped.any() else 0.0,
        "section_rise": rise,
    }
