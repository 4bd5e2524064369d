"""What a verification case reports: its checks against references, and the helpers that
measure a shell's state for them (energies, edge integrals, region energy densities)."""

from __future__ import annotations

from dataclasses import dataclass, field

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl

from tapecoil.core.dofs import global_scalar
from tapecoil.models.shell import NaghdiShell


@dataclass
class Check:
    """One computed quantity against its reference, with the tolerance it must meet."""

    name: str
    computed: float
    reference: float
    tolerance: float  # relative, or absolute when ``absolute``
    absolute: bool = False

    @property
    def error(self) -> float:
        if self.absolute:
            return abs(self.computed - self.reference)
        return abs(self.computed - self.reference) / abs(self.reference)

    @property
    def passed(self) -> bool:
        # a Python bool: numpy's bool would reach the JSON of ``tapecoil verify`` as 1.0
        return bool(np.isfinite(self.computed) and self.error <= self.tolerance)


@dataclass
class CaseResult:
    """A verification case: its checks and the numbers that describe the run."""

    case: str
    checks: list[Check]
    info: dict = field(default_factory=dict)
    model: object = field(default=None, repr=False)  # the solved NaghdiShell, for pictures

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)


def edge_integral(model: NaghdiShell, integrand, tag: int) -> float:
    return global_scalar(integrand * model.ds(tag), model.mesh.comm)


def energies(model: NaghdiShell) -> dict[str, float]:
    """Membrane, bending and shear energies [J] at the current state (the solve's quadrature)."""
    names = ("membrane", "bending", "shear")
    out = {name: global_scalar(getattr(model, f"energy_{name}"), model.mesh.comm) for name in names}
    out["total"] = out["membrane"] + out["bending"] + out["shear"]
    return out


def quadratic_energies(model: NaghdiShell) -> dict[str, float]:
    """Energies of the linearised shell at the current state q: E_i = d^2 E_i(0)[q, q] / 2.

    The second-order Taylor term of each energy form about the (stress-free) reference,
    assembled with the quadrature the solve uses. The state is restored afterwards.
    """
    direction = model.q.copy()
    model.q.x.array[:] = 0.0
    out = {}
    try:
        for name in ("membrane", "bending", "shear"):
            form = getattr(model, f"energy_{name}")
            second = ufl.derivative(ufl.derivative(form, model.q, direction), model.q, direction)
            out[name] = 0.5 * global_scalar(second, model.mesh.comm)
    finally:
        model.q.x.array[:] = direction.x.array
    out["total"] = out["membrane"] + out["bending"] + out["shear"]
    return out


def region_energy_density(model: NaghdiShell, V0, mask: np.ndarray) -> float:
    """Strain energy per unit area [J/m^2] over the owned cells flagged in ``mask`` (collective).

    The energy forms of the solve (same quadrature, PSRI included), weighted by the region's
    indicator, divided by the region's area.
    """
    chi = dolfinx.fem.Function(V0)
    chi.x.array[: len(mask)] = mask.astype(float)
    chi.x.scatter_forward()
    energy = sum(global_scalar(f, model.mesh.comm) for f in model.energy_forms(chi))
    return energy / global_scalar(chi * model.jacobian * model.dx, model.mesh.comm)


def solver_prefix(name: str) -> str:
    """The PETSc options prefix of a case's solver: -verify_tape_fold_snes_monitor."""
    return f"verify_{name.replace('-', '_')}_"
