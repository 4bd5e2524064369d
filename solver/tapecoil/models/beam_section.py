"""The section of a geometrically exact beam (:mod:`tapecoil.models.beam`): its stiffnesses, a
natural curvature and a constant energy per unit length; the tape's arc section and its
flattened strip. Units: SI."""

from __future__ import annotations

import math
from dataclasses import dataclass

from tapecoil.theory import arc_second_moment

__all__ = ["BeamSection"]


@dataclass(frozen=True)
class BeamSection:
    """The stiffnesses of a beam's section, in its frame (axis 1 along the beam, 2 and 3 across).

    Attributes:
        EA: axial stiffness [N].
        GA2, GA3: shear stiffnesses along axes 2 and 3 [N].
        GJ: torsional stiffness [N m^2].
        EI2, EI3: bending stiffnesses about axes 2 and 3 [N m^2].
        natural_curvature: the section's curvatures when free of moment (torsion, about 2, about
            3) [1/m].
        energy_offset: a constant energy per unit length [J/m].
        edge_relief: (M_R [N], D12 [N m], g [m^(1/2)/(N m)], sign, floor [1/m]): an energy per unit
            length taken off, (M_R + D12 kappa)^2 g / sqrt(kappa) with kappa = sign K2 held above
            the floor smoothly (the free edges' relief of a flattened coil,
            :meth:`flattened_strip`); g = 0: none.
    """

    EA: float
    GA2: float
    GA3: float
    GJ: float
    EI2: float
    EI3: float
    natural_curvature: tuple[float, float, float] = (0.0, 0.0, 0.0)
    energy_offset: float = 0.0
    edge_relief: tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 1.0, 1.0)

    def __post_init__(self):
        for name in ("EA", "GA2", "GA3", "GJ", "EI2", "EI3"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"beam section: {name} must be a positive number, got {value!r}")
        if len(self.natural_curvature) != 3 or not all(math.isfinite(k) for k in self.natural_curvature):
            raise ValueError(
                f"beam section: natural_curvature must be 3 numbers, got {self.natural_curvature!r}"
            )
        if not math.isfinite(self.energy_offset):
            raise ValueError(f"beam section: energy_offset must be a number, got {self.energy_offset!r}")
        relief = self.edge_relief
        if len(relief) != 5 or not all(math.isfinite(v) for v in relief) or relief[2] < 0 or relief[4] <= 0:
            raise ValueError(
                "beam section: edge_relief must be 5 numbers (M_R, D12, g >= 0, sign, floor > 0), "
                f"got {relief!r}"
            )

    @classmethod
    def flattened_strip(
        cls,
        D11: float,
        D12: float,
        D22: float,
        R: float,
        width: float,
        h: float,
        E: float,
        nu: float,
        coil_sign: float = 1.0,
        axial_stiffness: float | None = None,
    ) -> BeamSection:
        """A tape's section flattened in an opposite-sense coil, as a beam: its energy per unit
        length b w(kappa) = (b/2)(D11 kappa^2 + D22/R^2 + 2 D12 kappa/R) (physics brief Sec. 3 and
        10), kappa = ``coil_sign`` K2 the coil's curvature, is (b D11/2)(K2 - K2_n)^2 plus the
        constant (b/2)(D22 - D12^2/D11)/R^2 [J/m]: a beam of bending stiffness b D11 about axis 2
        whose natural curvature K2_n = -coil_sign D12/(D11 R) (a flattened strip curls the other
        way by nu/R when let go). The flat strip's other stiffnesses: EA = E b h, EI3 = E h b^3/12,
        GJ = G b h^3/3, shear 5/6 E b h/(2(1 + nu)). Rigidities D [N m], R, width b, h [m], E [Pa].

        With ``axial_stiffness`` S [N/m] (the wall's along the tape, E h isotropic), the free
        edges' relief of the coil is taken off: Delta U = (D22/R + D12 kappa)^2 / (D22 beta),
        beta = (S/(4 D22))^(1/4) sqrt(kappa) (:func:`tapecoil.theory.edge_layer`). The layer theory
        holds where the two edges' layers do not meet, beta b >= 6 say; below that curvature
        (and for kappa <= 0) kappa is held above it smoothly, so the relief stays bounded, and
        the law is not to be trusted there: a coil's flattened part, not a straight flattened
        strip.
        """
        G = E / (2 * (1 + nu))
        relief = (0.0, 0.0, 0.0, 1.0, 1.0)
        if axial_stiffness is not None:
            c0 = (axial_stiffness / (4 * D22)) ** 0.25
            relief = (D22 / R, D12, 1 / (D22 * c0), coil_sign, (6 / (c0 * width)) ** 2)
        return cls(
            EA=E * width * h,
            GA2=G * width * h * 5 / 6,
            GA3=G * width * h * 5 / 6,
            GJ=G * width * h**3 / 3,
            EI2=width * D11,
            EI3=E * h * width**3 / 12,
            natural_curvature=(0.0, -coil_sign * D12 / (D11 * R), 0.0),
            energy_offset=width / 2 * (D22 - D12**2 / D11) / R**2,
            edge_relief=relief,
        )

    @classmethod
    def rectangle(
        cls, E: float, nu: float, width: float, depth: float, torsion_constant: float | None = None
    ) -> BeamSection:
        """A solid rectangle ``width`` (along axis 2) by ``depth`` (along axis 3) [m] of an isotropic
        material E [Pa], nu; shear factor 5/6. ``torsion_constant`` J [m^4] defaults to Saint-Venant's
        series for the rectangle (0.1406 a^4 for a square of side a)."""
        G = E / (2 * (1 + nu))
        A = width * depth
        if torsion_constant is None:
            a, b = max(width, depth), min(width, depth)
            torsion_constant = a * b**3 * (1 / 3 - 0.21 * (b / a) * (1 - (b / a) ** 4 / 12))
        return cls(
            EA=E * A,
            GA2=G * A * 5 / 6,
            GA3=G * A * 5 / 6,
            GJ=G * torsion_constant,
            EI2=E * width * depth**3 / 12,
            EI3=E * depth * width**3 / 12,
        )

    @classmethod
    def circular_arc(cls, R: float, alpha: float, h: float, E: float, nu: float) -> BeamSection:
        """The thin circular-arc section of a tape spring: radius R [m], angle alpha [rad], wall
        thickness h [m], isotropic wall E [Pa], nu. Axis 2 runs across the width (the chord), axis 3
        towards the centre of curvature; the beam's line is the section's centroid.

        Thin-walled formulas (wall of thickness h along the arc, phi in [-alpha/2, alpha/2]):
        A = R alpha h; I2 about the centroid, :func:`tapecoil.theory.arc_second_moment` (the
        shell's end rotation under a small end moment matches M L/(E I2) within 3 %: `tapecoil
        verify tape-linear`); I3 = (R^3 h + R h^3/12)(alpha - sin alpha)/2 (the wall's own
        bending weighted by its inclination); Saint-Venant torsion of an open section,
        J = R alpha h^3 / 3; shear areas 5/6 A (the tape is slender: shear barely acts). Warping
        and the shear centre's offset from the centroid are not modelled.
        """
        for name, value in (("R", R), ("alpha", alpha), ("h", h), ("E", E)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"arc section: {name} must be a positive number, got {value!r}")
        if not 0 < alpha <= 2 * math.pi:
            raise ValueError(f"arc section: alpha must lie in (0, 2 pi], got {alpha!r}")
        G = E / (2 * (1 + nu))
        A = R * alpha * h
        I3 = R**3 * h * (alpha - math.sin(alpha)) / 2 + h**3 / 12 * R * (alpha - math.sin(alpha)) / 2
        return cls(
            EA=E * A,
            GA2=G * A * 5 / 6,
            GA3=G * A * 5 / 6,
            GJ=G * R * alpha * h**3 / 3,
            EI2=E * arc_second_moment(R, alpha, h),
            EI3=E * I3,
        )

    @staticmethod
    def arc_centroid_depth(R: float, alpha: float) -> float:
        """Depth of an arc section's centroid below its middle, towards the centre of curvature [m]:
        R (1 - sin(alpha/2) / (alpha/2))."""
        return R * (1 - math.sin(alpha / 2) / (alpha / 2))
