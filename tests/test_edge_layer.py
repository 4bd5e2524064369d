"""The edge layer of a flattened coil (tapecoil.theory.edge_layer) against a numerical solution
of the beam on an elastic foundation it stands for, and its tension against the configurational
balance of its own energy."""

import math

import numpy as np
import pytest
from scipy.integrate import simpson, solve_bvp, trapezoid

from tapecoil import theory as th

# the steel tape of Wilson et al. (2020) (h, alpha assumed: physics brief Sec. 10)
E, NU, H, R = 210e9, 0.3, 1.2e-4, 0.0192
BENDING = th.Bending.isotropic(E * H**3 / (12 * (1 - NU**2)), NU)
S = E * H


def _foundation_beam(D22, k, M0, span):
    """Lift w(x) of a free edge (x = 0) of a beam D22 w'''' + k w = 0 that sheds the moment M0:
    w''(0) = M0 / D22, no shear there, w and w' -> 0 at x = span (many decay lengths in); and
    its energy change int (-M0 w'' + D22 w''^2 / 2 + k w^2 / 2) dx against the unrelieved
    section. Solved in the units l = (D22 / k)^(1/4), w = M0 l^2 / D22 u: u'''' + u = 0."""
    scale = (D22 / k) ** 0.25
    xi = np.linspace(0.0, span / scale, 2001)

    def rhs(_, y):
        return np.vstack([y[1], y[2], y[3], -y[0]])

    def bc(y0, y1):
        return np.array([y0[2] - 1.0, y0[3], y1[0], y1[1]])

    sol = solve_bvp(rhs, bc, xi, np.zeros((4, xi.size)), tol=1e-10, max_nodes=100000)
    assert sol.success, sol.message
    xi = np.linspace(0.0, xi[-1], 40001)
    u, u2 = sol.sol(xi)[0], sol.sol(xi)[2]
    energy = M0**2 * scale / D22 * simpson(-u2 + 0.5 * u2**2 + 0.5 * u**2, x=xi)
    return xi * scale, M0 * scale**2 / D22 * u, energy


@pytest.mark.parametrize("ratio", [0.5, 0.9])
def test_closed_forms_match_the_foundation_beam(ratio):
    rho = ratio * R + H / 2
    layer = th.edge_layer(BENDING, S, R, rho)
    x, w, energy = _foundation_beam(BENDING.D22, S / rho**2, layer.moment, 20 * layer.decay_length)
    assert w[0] == pytest.approx(layer.rise, rel=1e-6)
    assert -w.min() == pytest.approx(layer.bearing_offset, rel=1e-4)
    assert x[np.argmin(w)] == pytest.approx(math.pi / 2 * layer.decay_length, rel=2e-3)
    assert 2 * energy == pytest.approx(-layer.energy_relief, rel=1e-6)
    assert abs(trapezoid(w, x)) < 1e-6 * layer.rise * layer.decay_length  # no mean lift


def test_isotropic_layer_in_closed_form():
    # beta = (3 (1 - nu^2))^(1/4) / sqrt(h rho), and the steel tape's edges on r_c/R = 0.9 lift
    # (rho/R + nu) / (2 sqrt(3 (1 - nu^2))) h = 0.364 h, wide apart (beta b = 26)
    rho = 0.9 * R + H / 2
    layer = th.edge_layer(BENDING, S, R, rho)
    assert layer.beta == pytest.approx((3 * (1 - NU**2)) ** 0.25 / math.sqrt(H * rho), rel=1e-12)
    assert layer.rise / H == pytest.approx((rho / R + NU) / (2 * math.sqrt(3 * (1 - NU**2))), rel=1e-12)
    assert layer.rise / H == pytest.approx(0.364, abs=1e-3)
    assert layer.beta * 1.5 * R > 20


@pytest.mark.parametrize("ratio", [0.4, 0.7, 0.9])
def test_tension_is_the_configurational_balance_of_the_relieved_energy(ratio):
    # T = kappa dU/dkappa - U of U(kappa) = b w(1/kappa) - Delta U(1/kappa), differentiated
    # numerically: what coiling_tension_with_edges states in closed form
    alpha = 1.5
    b = alpha * R

    def energy(kappa):
        plate = b * th.energy_density(1 / kappa, R, BENDING)
        return plate - th.edge_layer(BENDING, S, R, 1 / kappa).energy_relief

    kappa = 1 / (ratio * R + H / 2)
    dk = 1e-4 * kappa
    balance = kappa * (energy(kappa + dk) - energy(kappa - dk)) / (2 * dk) - energy(kappa)
    closed = th.coiling_tension_with_edges(BENDING, S, alpha, R, 1 / kappa)
    assert closed == pytest.approx(balance, rel=1e-6)
    eq_2_6 = th.coiling_tension_bending(BENDING, alpha, R, 1 / kappa)
    assert closed - eq_2_6 == pytest.approx(th.edge_layer(BENDING, S, R, 1 / kappa).tension_rise, rel=1e-9)
    assert closed > eq_2_6  # the relief falls as the coil tightens less than it grows


def test_edge_layer_refuses_non_physical_input():
    with pytest.raises(ValueError, match="rho, R and the axial stiffness"):
        th.edge_layer(BENDING, S, R, 0.0)


@pytest.mark.parametrize(
    ("hub", "sense", "listed"),
    [(0.0127, "opposite", True), (0.0127, "equal", False), (0.0604, "opposite", False)],
)
def test_the_theory_table_lists_the_edges_for_a_flattened_opposite_sense_coil(hub, sense, listed):
    from tapecoil.config import config_from_dict

    cfg = config_from_dict(
        {
            "hub": {"radius": hub},
            "coiling": {"hub_angle": 5.0, "tension": 10.0, "sense": sense},
        }
    )
    p = {x.key: x for x in th.predictions(cfg)}
    assert ("coiling_tension_edges" in p) == listed
    if listed:  # the benchmark's hub: Eq. 2.6 at the first turn's mid-surface plus the edges
        rho = cfg.hub.radius + cfg.tape.h / 2
        bending, stiffness = cfg.wall.bending, cfg.wall.axial_stiffness
        layer = th.edge_layer(bending, stiffness, cfg.tape.R, rho)
        assert p["coiling_tension_edges"].value == pytest.approx(
            th.coiling_tension_bending(bending, cfg.tape.alpha, cfg.tape.R, rho) + layer.tension_rise,
            rel=1e-12,
        )
        assert p["coiling_tension_edges"].value == pytest.approx(0.4561, abs=1e-4)
        assert p["edge_rise"].value == pytest.approx(layer.rise) and p["edge_relief"].value > 0


@pytest.mark.parametrize("sense", ["opposite", "equal"])
def test_fold_moment_with_edges_is_the_plate_form_less_the_relief(sense):
    """A fold's moment with its edge layers, minimised over the fold radius rho, against the
    plate form less the relief at rho = R, R Delta U(R), and the second-order shift of the
    minimum: with f = P - G (P = rho b w, stationary at R; G = rho Delta U), the minimum lies
    at f(R) - G'(R)^2 / (2 f''(R)), to the third order in the layers' scale eps = 1 / (alpha R
    beta) (their share of the moment is (1 +- nu) eps, a few per cent here): 3 eps^3 allows the
    third-order term a coefficient of order one."""
    alpha = 2.3562

    def relief(rho):
        return rho * th.edge_layer(BENDING, S, R, rho, sense).energy_relief

    def f(rho):
        return rho * R * alpha * th.energy_density(rho, R, BENDING, sense) - relief(rho)

    plate = th.fold_moment(BENDING, alpha, sense)
    sign = 1 if sense == "opposite" else -1
    eps = 1 / (alpha * R * th.edge_layer(BENDING, S, R, R).beta)
    assert f(R) == pytest.approx(plate * (1 - (1 + sign * NU) * eps), rel=1e-12)
    d = 1e-4 * R
    slope = (relief(R + d) - relief(R - d)) / (2 * d)
    curvature = (f(R + d) - 2 * f(R) + f(R - d)) / d**2
    expected = f(R) - slope**2 / (2 * curvature)
    assert th.fold_moment_with_edges(BENDING, S, alpha, R, sense) == pytest.approx(expected, rel=3 * eps**3)
