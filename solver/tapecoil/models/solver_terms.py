"""What the solvers take from a shell besides its energy: relaxation and the state's rounding.

The viscous term of pseudo-transient relaxation (:class:`tapecoil.core.stepping.Relaxation`
drives its coefficient) and the magnitudes behind the round-off floor of the convergence test
(:mod:`tapecoil.core.convergence`). Both take the shell first and are also its methods
(``model.relaxation(h_e)``, ``model.rounding_scale()``). The relaxation's first viscosity,
:func:`relaxation_scale`, is every relaxed solve's.
"""

from __future__ import annotations

import numpy as np
import ufl

# ``shell``/``model`` below: the NaghdiShell these functions serve as its methods, read, never
# imported (the shell imports them)


def rounding_scale(shell):
    """The magnitude of what each state component is added to, for the solver's round-off
    floor: |phi0| for the displacement (the position phi0 + u rounds to eps |phi0 + u|),
    1 for the director angles (the director's components, of size 1, round to eps)."""
    import dolfinx

    scale = dolfinx.fem.Function(shell.W)
    V, dofs = shell.W.sub(0).collapse()
    position = dolfinx.fem.Function(V)
    position.interpolate(lambda x: np.abs(shell.strip.geometry.phi0(x)))
    scale.x.array[dofs] = position.x.array
    _, angle_dofs = shell.W.sub(1).collapse()
    scale.x.array[angle_dofs] = 1.0
    return scale


def relaxation(shell, length_scale: float):
    """Viscous term for pseudo-transient relaxation: (coefficient, previous state, form).

    coefficient * [(u - u_prev).du + length_scale^2 (theta - theta_prev).dtheta] over the
    reference area; with the coefficient 0 it vanishes.
    """
    import dolfinx

    coefficient = dolfinx.fem.Constant(shell.mesh, 0.0)
    previous = dolfinx.fem.Function(shell.W)
    prev = ufl.split(previous)
    du, dtheta = ufl.split(shell.dq)[0], ufl.split(shell.dq)[1]
    form = (
        coefficient
        * (ufl.dot(shell.u - prev[0], du) + length_scale**2 * ufl.dot(shell.theta - prev[1], dtheta))
        * shell.jacobian
        * shell.dx
    )
    return coefficient, previous, form


def relaxation_scale(bending, element: float) -> float:
    """The first viscosity [N/m^3] of pseudo-transient relaxation (the ``scale`` of
    :class:`~tapecoil.core.stepping.Relaxation`) on a shell of the rigidities ``bending`` (a
    :class:`~tapecoil.theory.laminate.Bending`) and elements ``element`` [m] long."""
    # ten times the bending stiffness per unit area of the shortest wave the mesh holds (D11 / h_e^4):
    # the first pseudo-time step damps every bending mode, and the relaxation lowers it from there
    return 10 * bending.D11 / element**4
