"""A shell's edge tied to a beam's end node as a rigid section (Abaqus's MPC BEAM).

Every point X of the shell's edge keeps its place in the section frame of the beam's end: the
edge's position is phi(X) = r_e + Q (X - X_e) and its director is d(X) = Q n0(X), where r_e is
the end node's position, X_e its reference position and Q the rotation of its section since
the reference. Force and moment pass through the tie in full, and the section cannot deform
at the edge; how far from the edge that matters is measured in docs/hybrid.md.

The tie is collocated at the edge's nodes (a Gauss-Lobatto rule through them). A rigid motion
of the exact arc is not in the discrete space (the reference map is exact, the displacement
polynomial), but at the nodes the interpolated motion is exact, so the tie there costs a rigid
motion nothing. At Gauss points it held the interpolation error of the arc (about 1e-6 m with
four elements across) against the penalty: 0.014 J against the shell's 1e-5 J in a rigid turn
of 0.1 rad, and the solves failed beyond half a radian.

The tie is a penalty energy on the edge (per unit physical length)

    E = 1/2 (k_u |phi - r_e - Q (X - X_e)|^2 + k_d |d - Q n0|^2),

k_u = p E h / l_e and k_d = p E h^3 / l_e, l_e the shell's element length along the tape and p
the penalty factor: p times the stiffness of one element of membrane, and of bending, per unit
length of the edge. It is the energy of a :class:`~tapecoil.core.coupled_newton.DofCoupling`
whose parameters are the beam end's six dofs (its displacement and its rotation increment, see
:mod:`tapecoil.models.beam`). Q = R(theta_e) Q_n: the beam's rotations are incremental, so the
tie keeps Q_n, the end's rotation at the last accepted step, and moves it on at each
:meth:`RigidSectionTie.commit`, as the beam moves on its frames.
"""

from __future__ import annotations

import math

import dolfinx
import numpy as np
import ufl

from tapecoil.core.coupled_newton import DofCoupling
from tapecoil.core.dofs import global_scalar, owned_subspace_dofs
from tapecoil.core.rotation import rotation_matrices
from tapecoil.models.beam import rotation, vertices_at

__all__ = ["RigidSectionTie"]


class RigidSectionTie:
    """The shell ``shell`` (:class:`~tapecoil.models.shell.NaghdiShell`) along its edge tagged
    ``edge`` tied to the beam ``beam`` (:class:`~tapecoil.models.beam.GeometricallyExactBeam`) at
    its node ``end`` [m] (the reference position X_e), with penalty factor ``penalty`` (see the
    module); ``element_length``: the shell's element length along the tape at the edge [m];
    ``modulus``: the wall's in-plane Young's modulus [Pa]. Collective.
    """

    def __init__(self, shell, edge: int, beam, end, *, element_length: float, modulus: float, penalty=1e3):
        for name, value in (("penalty", penalty), ("element_length", element_length), ("modulus", modulus)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"rigid section tie: {name} must be a positive number, got {value!r}")
        self.shell, self.beam = shell, beam
        self.end = np.asarray(end, dtype=float)
        vertices = vertices_at(beam.mesh, self.end)
        dofs = []
        for sub in (0, 1):
            for i in range(3):
                found = owned_subspace_dofs(beam.W, (sub, i), 0, vertices)
                dofs.append(int(found[0]) if len(found) else -1)
        self.coupling = DofCoupling(shell.mesh, beam.q, dofs)
        self.turned = dolfinx.fem.Constant(shell.mesh, np.eye(3))  # Q_n

        h = shell.material.h
        self.k_u = penalty * modulus * h / element_length  # [N/m^2]
        self.k_d = penalty * modulus * h**3 / element_length  # [N]
        # the numbers as Constants, not literals: every tie then compiles to the same forms, and
        # a tie elsewhere or stiffer reuses them (compiling them takes about a minute)
        stiffness = dolfinx.fem.Constant(shell.mesh, np.array([self.k_u, self.k_d]))
        X_e = dolfinx.fem.Constant(shell.mesh, self.end)
        c = self.coupling.variable
        displacement = ufl.as_vector([c[0], c[1], c[2]])
        Q = rotation(ufl.as_vector([c[3], c[4], c[5]])) * self.turned
        X = shell.phi0
        self.position_gap = shell.phi - (X_e + displacement) - Q * (X - X_e)
        self.director_gap = shell.d - Q * shell.n0
        tangent = shell.J0[:, 1]  # along the edge, which lies across the tape (xi_1 fixed)
        self.line_element = ufl.sqrt(ufl.dot(tangent, tangent))
        density = (
            0.5
            * (
                stiffness[0] * ufl.dot(self.position_gap, self.position_gap)
                + stiffness[1] * ufl.dot(self.director_gap, self.director_gap)
            )
            * self.line_element
        )
        mesh = shell.mesh
        # collocated at the edge's nodes (Gauss-Lobatto points), where the discrete section
        # can follow a rigid motion exactly (see the module)
        self.measure = ufl.Measure(
            "ds",
            domain=mesh,
            subdomain_data=shell.strip.facet_tags,
            metadata={"quadrature_rule": "GLL", "quadrature_degree": 2 * shell.degree - 1},
        )(edge)
        tdim = mesh.topology.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        facets = shell.strip.facet_tags.find(edge)
        f2c = mesh.topology.connectivity(tdim - 1, tdim)
        cells = np.unique(np.concatenate([f2c.links(f) for f in facets])) if len(facets) else []
        self.coupling.set_energy(density, self.measure, shell.q, cells)

    def commit(self) -> None:
        """Accept the current state: Q_n <- R(theta_e) Q_n (call before the beam's own commit,
        which sets theta back to zero). Collective."""
        self.coupling.read()
        R = rotation_matrices(np.array(self.coupling.c.value[3:6]))[0]
        self.turned.value[:] = R @ np.asarray(self.turned.value)

    def gaps(self) -> tuple[float, float]:
        """The root-mean-square position gap [m] and director gap over the edge: a consistency
        check of the tie, which holds them to about force / k (collective)."""
        self.coupling.read()
        comm = self.shell.mesh.comm
        length = global_scalar(self.line_element * self.measure, comm)
        rms = [
            math.sqrt(
                max(global_scalar(ufl.dot(g, g) * self.line_element * self.measure, comm), 0.0) / length
            )
            for g in (self.position_gap, self.director_gap)
        ]
        return rms[0], rms[1]
