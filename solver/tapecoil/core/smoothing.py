"""The C1 smoothstep 3 s^2 - 2 s^3 on [0, 1], clamped outside: ramps of loads and obstacles."""

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
