"""The shell's internal virtual work over a step from q_old to q, energy-consistent.

The discrete gradient of the strain energy that the deployment's conserving time integration
uses (Simo and Tarnow 1992; Gonzalez 1996). The functions take the shell first and are also
its methods (``model.energy_secant_forms(q_old)``).
"""

from __future__ import annotations

import ufl

from tapecoil.models.director import director_secant

# ``shell``/``model`` below: the NaghdiShell these functions serve as its methods, read, never
# imported (the shell imports them)


def director_variation(shell, q_old):
    """The virtual director Dd_bar dtheta of the step from ``q_old`` to q (see director_secant)."""
    _, theta_old, _, _ = shell.kinematics(q_old)
    secant = director_secant(shell.theta_ref + theta_old, shell.theta_ref + shell.theta, shell.frame)
    return ufl.dot(secant, ufl.split(shell.dq)[1])


def energy_secant_forms(shell, q_old):
    """(membrane, bending, shear) internal virtual work, energy-consistent from q_old to q.

    Each strain is at most quadratic in (F, d), so with the stresses of the mean strain and
    the strain variations at the mean (F, d), and the director varied by its discrete
    derivative, the work in the direction of the step, dq = q - q_old, is exactly the
    change of each energy (Simo and Tarnow 1992; Gonzalez 1996):

        sum(forms)(q - q_old) = E(q) - E(q_old).

    The quadrature (PSRI split included) is that of :meth:`NaghdiShell.energy_forms`, so the
    identity holds point by point.
    """
    _, _, F0, d0 = shell.kinematics(q_old)
    F1, d1 = shell.F, shell.d
    strains = [0.5 * (a + b) for a, b in zip(shell.strains(F0, d0), shell.strains(F1, d1), strict=True)]
    du = ufl.split(shell.dq)[0]
    dF, dd = ufl.grad(du), director_variation(shell, q_old)
    F, d, grad_d = 0.5 * (F0 + F1), 0.5 * (d0 + d1), 0.5 * (ufl.grad(d0) + ufl.grad(d1))
    de = ufl.sym(F.T * dF)
    dk = ufl.sym(F.T * ufl.grad(dd) + dF.T * grad_d)
    dg = F.T * dd + dF.T * d
    work = shell.material.work_densities(shell.A, strains, (de, dk, dg))
    return shell.quadrature.integrate(*work)
