"""Smooth switches: the C1 smoothstep 3 s^2 - 2 s^3 on [0, 1], clamped outside (ramps of loads
and obstacles), and the smoothed bracket of a penalty contact."""

from __future__ import annotations

import numpy as np


def _polynomial(s):
    return s * s * (3.0 - 2.0 * s)


def smoothstep(x):
    """The smoothstep of numbers or numpy arrays (0 below 0, 1 above 1)."""
    return _polynomial(np.clip(x, 0.0, 1.0))


def smoothstep_ufl(x):
    """The smoothstep of a UFL expression, as in :func:`smoothstep`."""
    import ufl

    return _polynomial(ufl.min_value(ufl.max_value(x, 0.0), 1.0))


def penetration_ufl(gap, delta: float):
    """The penetration <gap> of a penalty contact: max(gap, 0), or, with ``delta`` > 0, its
    smooth version delta softplus(gap / delta) (UFL), written to be stable for either sign."""
    import ufl

    if delta > 0.0:
        x = gap / delta
        return delta * (ufl.max_value(x, 0.0) + ufl.ln(1.0 + ufl.exp(-abs(x))))
    return ufl.max_value(gap, 0.0)


def penetration_slope_ufl(gap, delta: float):
    """The slope d<gap>/d(gap) of :func:`penetration_ufl` (UFL): the step 0/1, or, with
    ``delta`` > 0, the logistic function of gap / delta, written to be stable for either sign.
    A penalty k <g>^2 / 2 pushes with k <g> times this slope."""
    import ufl

    if delta > 0.0:
        x = gap / delta
        below, above = ufl.exp(ufl.min_value(x, 0.0)), ufl.exp(-ufl.max_value(x, 0.0))
        return below / (below + above)
    return ufl.conditional(ufl.gt(gap, 0.0), 1.0, 0.0)
