"""Every analytic prediction for a configuration, as the table ``tapecoil theory`` prints."""

from __future__ import annotations

import math
from dataclasses import dataclass

from tapecoil.theory.coil_geometry import (
    coil_radius_during_deployment,
    coiled_length_from_radius,
    coiled_length_from_rotation,
    outer_radius_after_rotation,
    rotation_for_coiled_length,
    stored_energy,
    turn_radius,
)
from tapecoil.theory.coiling_tension import (
    coiling_regime,
    coiling_tension_bending,
    coiling_tension_tension_dominated,
)
from tapecoil.theory.deployment import deployment_time, seffen_rate, solve_deployment_ode
from tapecoil.theory.edge_layer import coiling_tension_with_edges, edge_layer
from tapecoil.theory.plate import (
    arc_second_moment,
    coil_energy_at_R,
    coil_stresses,
    energy_density,
    fold_moment,
    fold_radius,
    ploy_length,
)

# ``config`` below: a tapecoil.config.Config, read, never named: config sits above theory


@dataclass(frozen=True)
class Prediction:
    """One analytic prediction: a key for JSON, a label, the value, its unit and its source."""

    key: str
    label: str
    value: float
    unit: str
    source: str


def predictions(config) -> list[Prediction]:
    """Every analytic prediction of the physics brief for a configuration, in report order."""
    tp, r_hub = config.tape, config.hub.radius
    theta = config.coiling.hub_angle
    sense = config.coiling.sense
    wall = config.wall
    bending = wall.bending
    mu, b = coil_energy_at_R(bending, tp.R, sense), tp.b
    r_final = outer_radius_after_rotation(theta, r_hub, tp.h)
    x_coiled = min(coiled_length_from_rotation(theta, r_hub, tp.h), tp.L)
    theta_coiled = rotation_for_coiled_length(x_coiled, r_hub, tp.h)
    rho_first = turn_radius(0, r_hub, tp.h)
    sx, sy = coil_stresses(r_hub, tp.R, wall.stiffness_at(tp.h / 2), tp.h / 2, sense)
    k_hub = seffen_rate(mu, r_hub, tp.R, tp.alpha, tp.rho_l, tp.L)
    k_coil = seffen_rate(mu, r_final, tp.R, tp.alpha, tp.rho_l, tp.L)

    def k_growing(lam):
        r = coil_radius_during_deployment(lam, r_hub, tp.h, tp.L)
        return seffen_rate(mu, r, tp.R, tp.alpha, tp.rho_l, tp.L)

    ode = solve_deployment_ode(k_growing, 0.0)
    regime = coiling_regime(r_hub, tp.R)
    P = Prediction
    sign = "+" if sense == "opposite" else "-"
    if config.laminate.kind == "isotropic":
        out = [
            P("D", "flexural rigidity D", bending.D11, "N m", "E h^3 / (12 (1 - nu^2))"),
            P("mu", f"energy density of an {sense}-sense coil, mu", mu, "J/m^2", f"D (1 {sign} nu) / R^2"),
        ]
    else:
        clt = "D - B A^-1 B, classical lamination theory"
        out = [
            P("D11", "bending rigidity along the tape D11", bending.D11, "N m", clt),
            P("D22", "bending rigidity across the tape D22", bending.D22, "N m", clt),
            P("D12", "bending coupling D12", bending.D12, "N m", clt),
            P("D66", "twisting rigidity D66", bending.D66, "N m", clt),
            P("beta", "orthotropic ratio beta = D11 / D22", bending.beta, "-", "Eq. 3.5"),
            P(
                "mu",
                f"energy density of an {sense}-sense coil, w(R)",
                mu,
                "J/m^2",
                f"(D11 + D22 {sign} 2 D12) / (2 R^2)",
            ),
        ]
    out += [
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
            "fold moment plateau alpha (sqrt(D11 D22) + D12)",
            fold_moment(bending, tp.alpha),
            "N m",
            "Wuest 1954; physics brief Sec. 10",
        ),
        P(
            "fold_moment_equal",
            "fold moment plateau, equal sense, alpha (sqrt(D11 D22) - D12)",
            fold_moment(bending, tp.alpha, "equal"),
            "N m",
            "Seffen and Pellegrino 1999; physics brief Sec. 10",
        ),
        P(
            "fold_radius",
            "fold radius R sqrt(D11 / D22)",
            fold_radius(bending, tp.R),
            "m",
            "physics brief Sec. 10",
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
            energy_density(rho_first, tp.R, bending, sense),
            "J/m^2",
            "section 3",
        ),
        P(
            "stored_energy",
            "stored strain energy of the coiled length",
            stored_energy(theta_coiled, r_hub, tp.h, tp.R, tp.alpha, bending, sense),
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
        out.append(P("coiling_tension", "coiling tension", law(bending, tp.alpha, tp.R, r_hub), "N", source))
    if regime == "bending" and sense == "opposite":
        # the flattened first turn's free edges (mid-surface radius): what the plate leaves out
        layer = edge_layer(bending, wall.axial_stiffness, tp.R, rho_first)
        out += [
            P(
                "coiling_tension_edges",
                "coiling tension with the free edges' layers, mid-surface radius",
                coiling_tension_with_edges(bending, wall.axial_stiffness, tp.alpha, tp.R, rho_first),
                "N",
                "Eq. 2.6 + edge layer",
            ),
            P("edge_rise", "free edges' lift off the flattened first turn", layer.rise, "m", "edge layer"),
            P(
                "edge_relief",
                "energy per length the free edges relieve",
                layer.energy_relief,
                "J/m",
                "edge layer",
            ),
        ]
    out += [
        P("T_deploy_hub", "deployment time, r = r_hub", deployment_time(k_hub), "s", "Eq. 2.23"),
        P("t90_hub", "time to lambda = 0.9, r = r_hub", deployment_time(k_hub, 0.9), "s", "Eq. 2.20"),
        P("T_deploy_coil", "deployment time, r = coil radius", deployment_time(k_coil), "s", "Eq. 2.23"),
        P("T_deploy_ode", "deployment time, growing radius", ode.t100, "s", "Eq. 4.4"),
        P("t90_ode", "time to lambda = 0.9, growing radius", ode.t90, "s", "Eq. 4.4"),
        P(
            "ploy_length_arc",
            "ploy length, arc width",
            ploy_length(b, tp.R, tp.h, bending.beta),
            "m",
            "Eq. 3.5 (consistent)",
        ),
        P(
            "ploy_length_projected",
            "ploy length, projected width",
            ploy_length(tp.projected_width, tp.R, tp.h, bending.beta),
            "m",
            "Eq. 3.5 (consistent)",
        ),
    ]
    return out
