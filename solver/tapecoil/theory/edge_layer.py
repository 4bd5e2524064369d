"""The free edges of a flattened coil: the boundary layer the flattened-plate laws leave out.

In an opposite-sense coil of radius rho the section is pressed flat, so the flattened wall
carries the transverse moment M0 = D22/R + D12/rho per unit length (the bending moment that
holds its own curvature 1/R flat, plus the Poisson coupling of the coil's curvature). A free
edge cannot carry it. Near each edge the section curls back over a boundary layer: across the
width it bends as a beam of rigidity D22 on an elastic foundation, the foundation being the
coil's hoop strain, w / rho for a radial lift w, against the wall's axial stiffness S (E h for an
isotropic wall), so k = S / rho^2 (the edge zone of a cylindrical shell; Timoshenko and
Woinowsky-Krieger, *Theory of Plates and Shells*, Sec. 114 and Ch. 15). With
beta = (k / (4 D22))^(1/4) the layer of a semi-infinite beam under an end moment M0 (Hetenyi,
*Beams on Elastic Foundation*, 1946) gives

- the edge's lift off the flattened section, away from the axis: M0 / (2 D22 beta^2);
- the decay length 1 / beta, and a zero mean lift over the layer (the section's membrane force is
  unchanged); its deepest point, pi / (2 beta) from the edge, lies
  M0 e^(-pi/2) / (2 D22 beta^2) below the section, and there the coil bears on the hub, the
  flattened part standing that far off it;
- the energy relieved, M0^2 / (2 D22 beta) per edge: the plate's energy per unit length
  b w(rho) falls by Delta U = M0^2 / (D22 beta) for the two edges. Delta U does not depend on the
  width, so it matters most for narrow tapes;
- through the configurational balance T = kappa dU/dkappa - U (physics brief Sec. 5) of the
  relieved energy, the coiling tension rises above Eq. 2.6 by
  Delta T = ((3/2) M0^2 - 2 D12 M0 / rho) / (D22 beta). Eq. 2.6 falls to zero as rho -> R,
  Delta T does not: near r_c/R = 1 the edges carry most of the tension.

Isotropic wall: D22 = D, D12 = nu D, S = E h, beta = (3 (1 - nu^2))^(1/4) / sqrt(h rho). The
shell's coil has been checked against the layer on isotropic walls only (docs/notes/regimes.md); for
a laminate the same beam takes D22, D12 and S, and B = 0 is assumed (a symmetric layup). The
layer is linear in the lift, which is a fraction of h (0.36 h for the steel tape on
r_c/R = 0.9), and needs beta b >> 1 (two layers that do not meet; beta b = 26 there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tapecoil.theory.coiling_tension import coiling_tension_bending
from tapecoil.theory.laminate import Bending
from tapecoil.theory.plate import energy_density, sense_sign


@dataclass(frozen=True)
class EdgeLayer:
    """The boundary layer at each free edge of a flattened opposite-sense coil.

    Attributes:
        moment: M0, the transverse moment per unit length the flattened section carries and the
            free edge sheds [N m/m].
        beta: the layer's wavenumber (k / (4 D22))^(1/4) [1/m].
        D22: transverse bending rigidity [N m].
        D12: coupling rigidity [N m].
        rho: coil radius of the mid-surface [m].
    """

    moment: float
    beta: float
    D22: float
    D12: float
    rho: float

    @property
    def decay_length(self) -> float:
        """1 / beta [m]."""
        return 1.0 / self.beta

    @property
    def rise(self) -> float:
        """The edge's lift off the flattened section, away from the coil's axis [m]."""
        return self.moment / (2 * self.D22 * self.beta**2)

    @property
    def bearing_offset(self) -> float:
        """How far the layer dips below the flattened section, pi/(2 beta) from the edge [m]:
        the section bears on the hub there, its flattened part this far off the hub."""
        return self.rise * math.exp(-math.pi / 2)

    @property
    def energy_relief(self) -> float:
        """Delta U: the energy per unit length [J/m] both edges take off the plate's b w(rho)."""
        return self.moment**2 / (self.D22 * self.beta)

    @property
    def tension_rise(self) -> float:
        """Delta T = kappa d(-Delta U)/dkappa + Delta U [N]: what the edges add to Eq. 2.6."""
        m = self.moment
        return (1.5 * m**2 - 2 * self.D12 * m / self.rho) / (self.D22 * self.beta)


def edge_layer(
    bending: Bending, axial_stiffness: float, R: float, rho: float, sense: str = "opposite"
) -> EdgeLayer:
    """The edge layer of a flattened coil of mid-surface radius ``rho`` [m], of the coiling
    ``sense``.

    ``bending``: the wall's rigidities (D22, D12 enter); ``axial_stiffness``: S [N/m], the
    force per unit width that stretches the wall along the tape by a unit strain with its width
    free to contract (:attr:`Wall.axial_stiffness`: E h for an isotropic wall); ``R``: the
    section's radius [m]. In the equal sense the coil's curvature couples to the flattening with
    the other sign: M0 = D22/R - D12/rho (in magnitude).
    """
    if rho <= 0 or R <= 0 or axial_stiffness <= 0:
        raise ValueError(
            f"edge_layer needs rho, R and the axial stiffness > 0 (got {rho}, {R}, {axial_stiffness})"
        )
    moment = bending.D22 / R + sense_sign(sense) * bending.D12 / rho
    beta = (axial_stiffness / (4 * bending.D22)) ** 0.25 / math.sqrt(rho)
    return EdgeLayer(moment, beta, bending.D22, bending.D12, rho)


def coiling_tension_with_edges(
    bending: Bending, axial_stiffness: float, alpha: float, R: float, rho: float
) -> float:
    """Eq. 2.6 at ``rho`` plus the edge layers' :attr:`EdgeLayer.tension_rise` [N]: the
    configurational balance of the relieved coil, T = kappa dU/dkappa - U with
    U = b w(rho) - Delta U."""
    return (
        coiling_tension_bending(bending, alpha, R, rho)
        + edge_layer(bending, axial_stiffness, R, rho).tension_rise
    )


def fold_moment_with_edges(
    bending: Bending, axial_stiffness: float, alpha: float, R: float, sense: str = "opposite"
) -> float:
    """The steady moment of a localised fold [N m] with its free edges' layers: the minimum
    over the fold radius rho of rho (b w(rho) - Delta U(rho)), b = R alpha, the plate's energy
    per unit length less what the two edge layers relieve (:attr:`EdgeLayer.energy_relief`),
    where :func:`~tapecoil.theory.plate.fold_moment` minimises rho b w(rho) alone. Below that
    plate form by about (1 +- nu) / (alpha R beta) of it, beta at rho = R: a few per cent for
    a thin tape of a narrow section."""
    from scipy.optimize import minimize_scalar

    b = R * alpha

    def per_radian(rho: float) -> float:
        relief = edge_layer(bending, axial_stiffness, R, rho, sense).energy_relief
        return rho * (b * energy_density(rho, R, bending, sense) - relief)

    best = minimize_scalar(
        per_radian, bounds=(0.2 * R, 5.0 * R), method="bounded", options={"xatol": 1e-10 * R}
    )
    return float(best.fun)
