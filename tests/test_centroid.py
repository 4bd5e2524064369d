"""The section centroid read from a shell's nodes."""

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.measures.centroid import section_centroid
from tapecoil.models.beam_section import BeamSection
from tapecoil.models.materials import shell_material
from tapecoil.models.nodes import Nodes
from tapecoil.models.problem import ShellProblem


def test_the_arc_sections_centroid_lies_at_the_arcs_centroid_depth():
    """The benchmark tape at rest: every section's centroid on its middle at the arc's centroid
    depth R (1 - sin(a/2)/(a/2)), to 1e-4 of it on 8 Q2 elements across (Simpson's rule on the
    arc's nodes: measured 1e-5, and 1.5e-4 on 4); a rigid shift of the state moves it by the
    shift."""
    config = Config()
    tp = config.tape
    problem = ShellProblem(
        StripGeometry(tp.R, tp.b, 0.1), MeshResolution(8, 8), shell_material(config), comm=MPI.COMM_WORLD
    )
    depth = BeamSection.arc_centroid_depth(tp.R, tp.alpha)
    c = section_centroid(problem.model, 0.05, MPI.COMM_WORLD)
    assert c[0] == pytest.approx(0.05, abs=1e-12) and abs(c[1]) < 1e-12
    assert c[2] == pytest.approx(depth, rel=1e-4)
    shift = np.array([1e-3, -2e-3, 3e-3])
    nodes = Nodes(problem.model)
    problem.model.q.x.array[nodes.u_dofs] += shift
    assert section_centroid(problem.model, 0.05, MPI.COMM_WORLD) == pytest.approx(c + shift, abs=1e-12)


@pytest.mark.mpi
def test_two_ranks_read_the_centroid_as_one():
    assert MPI.COMM_WORLD.size > 1
    config = Config()
    tp = config.tape
    read = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        problem = ShellProblem(
            StripGeometry(tp.R, tp.b, 0.1), MeshResolution(8, 8), shell_material(config), comm=comm
        )
        read.append(section_centroid(problem.model, 0.0625, comm))
    assert read[0] == pytest.approx(read[1], abs=1e-15)
