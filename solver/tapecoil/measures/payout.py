"""What a driven hub's payout measures: the coiling tension on the outer turn and at the root, and
the hub torque, against the laws of a flattened coil as lambda grows.

The laws (physics brief Sec. 5 and 10), with rho a turn's mid-surface radius:

- the tension a flattened coil takes, Eq. 2.6: T_c(rho) = (D b / 2)(1/rho^2 - 1/R^2); with the
  growing radius of a coil holding (1 - lambda) L: Eq. 4.5. Its radius, r(lambda)^2 = r_hub^2 +
  h (1 - lambda) L / pi, spreads the coil's length over the annulus beyond the hub, so it is the
  coil's outer face on average; taken for the mid-surface spiral, which starts at r_hub + h/2,
  rho(lambda)^2 = (r_hub + h/2)^2 + h (1 - lambda) L / pi is the mid-surface radius where the
  tape comes off the coil, and equals the first turn's at lambda = 1;
- by the configurational force balance T - N = T_c(rho) wherever the tape lies flat on a turn of
  radius rho, so at the root it is T_c(r_hub + h/2) whatever lambda;
- a shell's coil is flattened but for its free edges' boundary layer, which adds its share to
  T_c (:mod:`tapecoil.theory.edge_layer`, opposite sense): T_c + Delta T at the outer turn;
  the root's clamp holds the whole width flat and reads T_c;
- steady coiling's hub torque, from the energy balance of a step: rho (T + b w(rho)), rho the
  outermost turn's radius, where the tape comes on or off.

The per-step readings oscillate as nodes pass the tangent point; the summary gives, per band of
lambda, their mean and spread.
"""

from __future__ import annotations

import math

import numpy as np

from tapecoil import theory

OUTER_STATION = (1.0, 3.0)
"""The band of winding behind the tangent point [rad] where the outer turn's axial force is read:
past the coil's side of the ploy region (about 1 rad on the benchmark) and within half a turn."""

CLIMB_CLEARANCE = 1.0
"""Winding [rad] kept between the station and the place where the outer turn climbs over the
root end: the obstacle's ramp there bends the tape and disturbs N over about a radian."""

STATION_MARGIN = 0.25
"""Winding [rad] kept between the outer turn's station and the root; below OUTER_STATION[0] +
STATION_MARGIN of hub angle there is no station and the outer turn's columns are empty."""

LAMBDA_BANDS = tuple(round(0.1 * k, 1) for k in range(1, 10))


def tension_law(rho, config) -> float | np.ndarray:
    """Eq. 2.6 at the mid-surface radius rho [m] of the configured tape [N]."""
    tp = config.tape
    return theory.coiling_tension_bending(config.wall.bending, tp.alpha, tp.R, rho)


def tension_law_with_edges(rho: float, config) -> float | str:
    """Eq. 2.6 plus the free edges' share at the mid-surface radius rho [m] [N]; empty for an
    equal-sense coil, for which the edge layer is not derived."""
    if config.coiling.sense != "opposite":
        return ""
    tp, wall = config.tape, config.wall
    return theory.coiling_tension_with_edges(wall.bending, wall.axial_stiffness, tp.alpha, tp.R, rho)


def eq_4_5(lam, config) -> float | np.ndarray:
    """Eq. 4.5 with the mid-surface radius rho(lambda) of the coil where the tape leaves it [N]."""
    tp = config.tape
    rho = theory.coil_radius_during_deployment(lam, config.hub.radius + tp.h / 2, tp.h, tp.L)
    return tension_law(rho, config)


def steady_torque(rho: float, pull: float, config) -> float:
    """Steady coiling's hub torque rho (T + b w(rho)) [N m] (the energy balance of a step)."""
    tp = config.tape
    return rho * (pull + tp.b * theory.energy_density(rho, tp.R, config.wall.bending, config.coiling.sense))


def outer_station(angle: float) -> float:
    """The winding behind the tangent point [rad] at which to read the outer turn: in
    OUTER_STATION (cut short so that it stays STATION_MARGIN ahead of the root) and as far as the
    band allows from the outer turn's climb over the root end, which lies (hub angle mod 2 pi)
    behind the tangent point."""
    climb = angle % (2 * math.pi)
    candidates = np.linspace(OUTER_STATION[0], min(OUTER_STATION[1], angle - STATION_MARGIN), 41)
    gap = np.abs(candidates - climb)
    gap = np.minimum(gap, 2 * math.pi - gap)
    return float(candidates[np.argmax(gap)])


OUTER_TURN_COLUMNS = (
    "station_winding",
    "outer_turn_radius",
    "coiling_tension_outer",
    "eq_2_6_outer",
    "eq_2_6_edges_outer",
    "eq_4_5",
    "steady_torque",
)


def outer_turn_tension(tape, sections, pull: float, lam: float, angle: float) -> dict:
    """The history columns of the outer turn (OUTER_TURN_COLUMNS) at the current state, empty
    where the coil is too short for a station (collective).

    ``sections``: the tape's :class:`~tapecoil.measures.section_forces.SectionForces`; ``pull``
    the tension at the free end [N], ``lam`` the deployed fraction, ``angle`` the hub angle.
    """
    if angle < OUTER_STATION[0] + STATION_MARGIN:
        return dict.fromkeys(OUTER_TURN_COLUMNS, "")
    sections = sections()
    config = tape.config
    line = tape.centre_line()
    radius, _ = tape.contact.polar(sections["columns"].T)
    cut_radius = 0.5 * (radius[:-1] + radius[1:])
    psi = np.interp(sections["xi1"], line["xi1"], line["psi"])
    behind = outer_station(angle)
    k = int(np.argmin(np.abs(psi - (angle - behind))))
    rho = float(cut_radius[k])
    return {
        "station_winding": behind,
        "outer_turn_radius": rho,
        "coiling_tension_outer": pull - float(sections["axial_force"][k]),
        "eq_2_6_outer": float(tension_law(rho, config)),
        "eq_2_6_edges_outer": tension_law_with_edges(rho, config),
        "eq_4_5": float(eq_4_5(lam, config)),
        "steady_torque": steady_torque(rho, pull, config),
    }


def _band(rows: list[dict], lo: float, hi: float, key: str, reference) -> dict | None:
    band = [r for r in rows if lo <= r["lambda"] < hi and r.get(key, "") != "" and reference(r) != ""]
    if not band:
        return None
    values = np.array([float(r[key]) for r in band])
    ref = np.array([float(reference(r)) for r in band])
    mean, ref_mean = float(values.mean()), float(ref.mean())
    return {
        "lambda": [lo, hi],
        "steps": len(band),
        "mean": mean,
        "spread": float(values.max() - values.min()),
        "reference": ref_mean,
        "error": mean / ref_mean - 1 if ref_mean else float("nan"),
    }


def payout_measures(config, history: list[dict]) -> dict:
    """The payout's summary: per band of lambda (0.1 wide, from the lowest band reached to 0.9),
    the mean and spread of the outer turn's T - N against Eq. 4.5 and against Eq. 2.6 at its
    measured radius without and with its free edges' share, of the root's T - N against Eq. 2.6
    at the first turn, and of the hub torque from the reactions against steady coiling; and the
    largest error of each over the bands."""
    tp = config.tape
    root_law = float(tension_law(config.hub.radius + tp.h / 2, config))
    quantities = {
        "outer_turn_tension_vs_eq_4_5": ("coiling_tension_outer", lambda r: r["eq_4_5"]),
        "outer_turn_tension_vs_eq_2_6": ("coiling_tension_outer", lambda r: r["eq_2_6_outer"]),
        "outer_turn_tension_vs_eq_2_6_edges": (
            "coiling_tension_outer",
            lambda r: r.get("eq_2_6_edges_outer", ""),
        ),
        "root_tension_vs_eq_2_6": ("coiling_tension", lambda r: root_law),
        "hub_torque_vs_steady": ("hub_torque_reaction", lambda r: r["steady_torque"]),
    }
    rows = [r for r in history if r.get("phase") == "payout"]
    out: dict = {"lambda_start": rows[0]["lambda"] if rows else None}
    out["lambda_end"] = rows[-1]["lambda"] if rows else None
    for name, (key, reference) in quantities.items():
        bands = [_band(rows, lo, lo + 0.1, key, reference) for lo in LAMBDA_BANDS[:-1]]
        bands = [b for b in bands if b is not None]
        out[name] = {
            "bands": bands,
            "max_error": max((abs(b["error"]) for b in bands), default=None),
        }
    return out
