"""The C compiler's options for every form and expression tapecoil compiles.

FFCx writes each kernel as straight-line C, which DOLFINx compiles with ``-O2 -g0``. The
shell's Jacobian kernel (the Hessian of the Naghdi strain energy at the Gauss points of a Q2
cell) is long sums of products, which the compiler may not reorder under strict IEEE rules,
and square roots that set ``errno``. Letting it reassociate sums and take the square root as
an instruction (no ``errno``, no traps, zeros without sign) vectorises them: the shell's
assembly takes about four fifths of the time. Nothing here is finite-math-only: a NaN still
propagates to the checks that stop a run on it. No ``-march=native``: a cache of kernels
stays usable on another processor of a cluster that shares it.

The price is round-off that depends on where the data lie in memory (a vectorised loop peels
its first terms by alignment): the same run on another number of ranks agrees with itself to
round-off amplified by the solves, about 1e-7 of a result instead of 1e-11, far inside every
validated tolerance. The optimisation level is DOLFINx's (its default, or what a caller set
in ``dolfinx.jit.DOLFINX_DEFAULT_JIT_OPTIONS``); a user's ``dolfinx_jit_options.json`` gives
other arguments. Build every form with :func:`form` and every expression with
:func:`expression`.
"""

from __future__ import annotations

import dolfinx
import dolfinx.jit

__all__ = ["REASSOCIATION", "expression", "form", "jit_options"]

# the flags that let the compiler reorder a sum and inline a square root
REASSOCIATION = ["-fno-math-errno", "-fno-trapping-math", "-fassociative-math", "-fno-signed-zeros"]


def jit_options() -> dict:
    """DOLFINx's JIT options (its defaults and a user's files) with :data:`REASSOCIATION`
    added to the compiler's arguments."""
    options = dolfinx.jit.get_options()
    arguments = list(options.get("cffi_extra_compile_args") or [])
    return {"cffi_extra_compile_args": arguments + [f for f in REASSOCIATION if f not in arguments]}


def form(ufl_form, **kwargs):
    """``dolfinx.fem.form`` with tapecoil's compiler options (``ufl_form`` may be a list or
    nested lists of forms, as DOLFINx takes them)."""
    return dolfinx.fem.form(ufl_form, jit_options=jit_options(), **kwargs)


def expression(ufl_expression, points, **kwargs):
    """``dolfinx.fem.Expression`` at reference ``points`` with tapecoil's compiler options."""
    return dolfinx.fem.Expression(ufl_expression, points, jit_options=jit_options(), **kwargs)
