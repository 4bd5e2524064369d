"""Expressions compile once for every model built alike (tapecoil.core.expression)."""

import ffcx.naming
from mpi4py import MPI

from tapecoil.core.expression import expression_at
from tapecoil.models.beam_problem import BeamProblem
from tapecoil.models.beam_section import BeamSection
from tapecoil.verification.beam import fixed_frame, straight_line


def kernel_name(expression) -> str:
    """The name FFCx gives the compiled kernel of a dolfinx Expression (its cache key)."""
    return ffcx.naming.compute_signature([(expression.ufl_expression, expression.X())], "")


def test_two_beams_built_alike_share_their_kernels():
    """The beam's curvature holds a derivative by a ufl.variable, whose signature UFL takes
    from a global count: built raw, each beam's curvature would be a kernel of its own (and a
    compilation each time a hybrid's window moves). Through expression_at, two beams on two
    meshes share every kernel."""
    section = BeamSection.rectangle(E=2.1e11, nu=0.3, width=0.02, depth=0.01)
    beams = [
        BeamProblem(straight_line, 1.0, n, section, fixed_frame, comm=MPI.COMM_SELF).model for n in (4, 5)
    ]
    points = beams[0]._next_curvature.X()
    raw = [ffcx.naming.compute_signature([(beam.curvature, points)], "") for beam in beams]
    assert raw[0] != raw[1]  # what expression_at is there for
    for name in ("_next_frame", "_next_curvature"):
        first, second = (kernel_name(getattr(beam, name)) for beam in beams)
        assert first == second, name
    assert kernel_name(expression_at(beams[0].curvature, points)) == kernel_name(beams[1]._next_curvature)
