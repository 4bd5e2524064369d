"""The C compiler's options for every form and expression tapecoil compiles.

FFCx writes each kernel as straight-line C, DOLFINx compiles it with ``-O2 -g0``. The shell's
Jacobian kernel (the Hessian of the Naghdi strain energy at 9 Gauss points of a Q2 cell) is
long sums of products, which the compiler may not reorder under strict IEEE rules, and square
roots that set ``errno``. Letting it reassociate sums and treat the square root as an
instruction (no ``errno``, no traps, zeros without sign) vectorises them: the shell's Jacobian
assembles in about four fifths of the time (docs/hybrid.md gives the measurement,
``tools/shell_kernel_cost.py --dolfinx-flags`` the comparison). The results change at
round-off only. Nothing here is finite-math-only: a NaN still propagates
to the checks that stop a run on it. No ``-march=native``: a cache of kernels stays usable on
another processor.

Build every form with :func:`form` and every expression with :func:`expression`.
"""

from __future__ import annotations

import dolfinx

__all__ = ["JIT_OPTIONS", "expression", "form"]

JIT_OPTIONS = {
    "cffi_extra_compile_args": [
        "-O2",
        "-g0",
        "-fno-math-errno",
        "-fno-trapping-math",
        "-fassociative-math",
        "-fno-signed-zeros",
    ]
}


def form(ufl_form, **kwargs):
    """``dolfinx.fem.form`` with tapecoil's compiler options (``ufl_form`` may be a list or
    nested lists of forms, as DOLFINx takes them)."""
    return dolfinx.fem.form(ufl_form, jit_options=JIT_OPTIONS, **kwargs)


def expression(ufl_expression, points, **kwargs):
    """``dolfinx.fem.Expression`` at reference ``points`` with tapecoil's compiler options."""
    return dolfinx.fem.Expression(ufl_expression, points, jit_options=JIT_OPTIONS, **kwargs)
