"""Expressions evaluated at points of the reference cell, compiled once for every mesh.

FFCx names an Expression's kernel after its UFL signature, and UFL signs a ``ufl.variable`` by
its global count: an expression holding one (a derivative taken by ``ufl.diff``) gets a new
signature, and a new compilation, each time it is built, for every new mesh or model. Applying
the derivatives and removing the variables first gives the same signature, and so the same
cached kernel, to every build of the same expression.
"""

import dolfinx
import numpy as np
import ufl
from ufl.algorithms.apply_algebra_lowering import apply_algebra_lowering
from ufl.algorithms.apply_derivatives import apply_derivatives
from ufl.algorithms.transformer import strip_variables

from tapecoil.core import jit


def expression_at(expr, points: np.ndarray) -> dolfinx.fem.Expression:
    """A :class:`dolfinx.fem.Expression` of ``expr`` (UFL) at ``points`` of the reference cell,
    its kernel independent of the variables' counts."""
    if not isinstance(expr, ufl.core.expr.Expr):
        raise TypeError(f"an expression must be a UFL expression, got {type(expr).__name__}")
    return jit.expression(strip_variables(apply_derivatives(apply_algebra_lowering(expr))), points)
