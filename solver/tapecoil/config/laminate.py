"""The [laminate] section: the tape's wall as a laminate, in place of the isotropic tape.E and tape.nu."""

from __future__ import annotations

import math
from dataclasses import dataclass

from tapecoil.config.params import ConfigError, param


@dataclass
class LaminateConfig:
    """The tape's wall as a laminate, in place of the isotropic tape.E and tape.nu.

    The wall's axes: 1 along the tape, 2 across its width, z through the thickness towards the
    concave side of the section (the centre of its curvature; in opposite-sense coiling the
    coil's outer face). Matrices in Voigt order (11, 22, 12), the engineering shear strain
    2 e_12 (classical lamination theory: N = A eps + B kappa, M = B eps + D kappa).

    Attributes:
        kind: 'isotropic' (no laminate: tape.E and tape.nu), 'plies' (the plies below,
            classical lamination theory) or 'matrices' (A, B, D, H given) [-].
        angles: ('plies') fibre angle of each ply from the tape's length axis, turned towards
            its width axis, listed from the face at z = -h/2 (the hub side in opposite sense)
            up [deg].
        thicknesses: ('plies') each ply's thickness [m]; they add up to tape.h.
        E1: ('plies') ply modulus along the fibres [Pa], one value for every ply or one per ply.
        E2: ('plies') ply modulus across the fibres [Pa], one or one per ply.
        nu12: ('plies') major Poisson ratio of the ply [-], one or one per ply.
        G12: ('plies') in-plane shear modulus of the ply [Pa], one or one per ply.
        G13: ('plies') transverse shear modulus along the fibres [Pa], one or one per ply;
            empty: G12.
        G23: ('plies') transverse shear modulus across the fibres [Pa], one or one per ply;
            empty: G12.
        A: ('matrices') in-plane stiffness [A11, A12, A16, A22, A26, A66] [N/m].
        B: ('matrices') coupling stiffness [B11, B12, B16, B22, B26, B66] [N]; empty: 0.
        D: ('matrices') bending stiffness [D11, D12, D16, D22, D26, D66] [N m].
        H: ('matrices') transverse shear stiffness [H11, H12, H22], order (13, 23), the shear
            correction included [N/m]; empty: 5/6 A66 on the diagonal, 0 off it.
    """

    kind: str = param("isotropic", "", ("isotropic", "plies", "matrices"))
    angles: list = param([], "deg")
    thicknesses: list = param([], "m")
    E1: list = param([], "Pa")
    E2: list = param([], "Pa")
    nu12: list = param([], "-")
    G12: list = param([], "Pa")
    G13: list = param([], "Pa")
    G23: list = param([], "Pa")
    A: list = param([], "N/m")
    B: list = param([], "N")
    D: list = param([], "N m")
    H: list = param([], "N/m")

    PLY_KEYS = ("angles", "thicknesses", "E1", "E2", "nu12", "G12", "G13", "G23")
    MATRIX_KEYS = ("A", "B", "D", "H")

    def check(self) -> None:
        unused = {
            "isotropic": self.PLY_KEYS + self.MATRIX_KEYS,
            "plies": self.MATRIX_KEYS,
            "matrices": self.PLY_KEYS,
        }[self.kind]
        given = [k for k in unused if getattr(self, k)]
        other = {"plies": "matrices", "matrices": "plies"}
        if given:
            raise ConfigError(
                f"laminate.{given[0]} does not act with laminate.kind = {self.kind!r}: "
                + (
                    "set laminate.kind = 'plies' or 'matrices', or leave it out"
                    if self.kind == "isotropic"
                    else f"leave it out, or set laminate.kind = {other[self.kind]!r}"
                )
            )
        if self.kind == "plies":
            self._check_plies()
        elif self.kind == "matrices":
            self._check_matrices()

    def _check_plies(self) -> None:
        n = len(self.angles)
        if n == 0:
            raise ConfigError("laminate.angles must list at least one ply with laminate.kind = 'plies'")
        if len(self.thicknesses) != n:
            raise ConfigError(
                f"laminate.thicknesses has {len(self.thicknesses)} values for {n} plies (laminate.angles): "
                "give one thickness per ply"
            )
        for key in ("thicknesses", "E1", "E2", "G12", "G13", "G23"):
            values = getattr(self, key)
            if key in ("E1", "E2", "G12") and not values:
                raise ConfigError(f"laminate.{key} is needed with laminate.kind = 'plies'")
            if len(values) not in (0, 1, n) or (key == "thicknesses" and len(values) != n):
                raise ConfigError(f"laminate.{key} must hold one value for every ply or one per ply ({n})")
            if any(v <= 0 for v in values):
                raise ConfigError(f"laminate.{key} = {values!r} is out of range: must be > 0")
        if len(self.nu12) not in (1, n):
            raise ConfigError(f"laminate.nu12 must hold one value for every ply or one per ply ({n})")
        for e1, e2, v12 in zip(*(self.per_ply(k) for k in ("E1", "E2", "nu12")), strict=True):
            # a positive-definite ply: 1 - nu12 nu21 > 0 with nu21 = nu12 E2 / E1
            if not 0 <= v12 < math.sqrt(e1 / e2):
                raise ConfigError(
                    f"laminate.nu12 = {v12:g} is out of range for E1 = {e1:g} Pa, E2 = {e2:g} Pa: must "
                    f"be in [0, sqrt(E1/E2)) = [0, {math.sqrt(e1 / e2):.4g}) for a ply that stores energy"
                )
        if any(abs(a) > 360 for a in self.angles):
            raise ConfigError(
                f"laminate.angles = {self.angles!r} is out of range: must be in [-360, 360] [deg]"
            )

    def _check_matrices(self) -> None:
        order = {3: "11, 12, 22", 6: "11, 12, 16, 22, 26, 66"}
        for key, n, needed in (("A", 6, True), ("B", 6, False), ("D", 6, True), ("H", 3, False)):
            values = getattr(self, key)
            if (needed or values) and len(values) != n:
                raise ConfigError(
                    f"laminate.{key} must hold {n} values ({order[n]}) with laminate.kind = 'matrices', "
                    f"got {len(values)}"
                )

    def per_ply(self, key: str) -> list[float]:
        """A ply property's value for every ply (a single value repeated; G13, G23 default to G12)."""
        values = getattr(self, key) or (self.G12 if key in ("G13", "G23") else [])
        return list(values) * len(self.angles) if len(values) == 1 else list(values)

    @property
    def total_thickness(self) -> float:
        """The plies' thicknesses added up [m] (0 when the wall is not given by plies)."""
        return float(sum(self.thicknesses))

    def wall(self, tape):
        """The tape's wall (:class:`tapecoil.theory.laminate.Wall`): A, B, D, H from ``tape``'s
        E, nu and h (a :class:`~tapecoil.config.sections.TapeConfig`), from the plies, or as given."""
        from tapecoil.theory.laminate import Wall  # lazy: a configuration loads without scipy

        if self.kind == "isotropic":
            return Wall.isotropic(tape.E, tape.nu, tape.h)
        if self.kind == "plies":
            return Wall.from_plies(
                *(self.per_ply(k) for k in ("E1", "E2", "nu12", "G12", "G13", "G23")),
                [math.radians(a) for a in self.angles],
                self.thicknesses,
            )
        A = _symmetric3(self.A)
        shear = 5 / 6 * A[2][2]  # the in-plane shear stiffness standing for the transverse one
        H = [[self.H[0], self.H[1]], [self.H[1], self.H[2]]] if self.H else [[shear, 0.0], [0.0, shear]]
        return Wall.from_matrices(A, _symmetric3(self.B or [0.0] * 6), _symmetric3(self.D), H, tape.h)


def _symmetric3(v: list[float]) -> list[list[float]]:
    """The symmetric 3 x 3 matrix of its upper triangle [11, 12, 16, 22, 26, 66]."""
    a11, a12, a16, a22, a26, a66 = v
    return [[a11, a12, a16], [a12, a22, a26], [a16, a26, a66]]
