"""Boundary kinematics of shell edges: clamps and rigid-body rotations about an axis.

A rotated edge gets rigid-body kinematics, displacement and director together: prescribing only
the director of a Naghdi shell edge lets a thin layer there shear instead of turning the shell.
"""

from __future__ import annotations

from dataclasses import dataclass

import dolfinx
import numpy as np

from tapecoil.core.dofs import owned_subspace_dofs
from tapecoil.core.rotation import rotation_matrix
from tapecoil.models.shell import NaghdiShell


def facet_condition(model: NaghdiShell, sub: tuple[int, ...], facets: np.ndarray):
    """A Dirichlet condition on the (sub-)space ``W.sub(i).sub(j)...`` over ``facets``.

    Returns (value, bc): the prescribed values live in the collapsed-space Function ``value``
    (zero until set), so that load stepping can change them in place.
    """
    space = model.W
    for i in sub:
        space = space.sub(i)
    collapsed, _ = space.collapse()
    dofs = dolfinx.fem.locate_dofs_topological((space, collapsed), model.mesh.topology.dim - 1, facets)
    value = dolfinx.fem.Function(collapsed)
    return value, dolfinx.fem.dirichletbc(value, dofs, space)


def owned_edge_dofs(model: NaghdiShell, tag: int, sub: tuple[int, ...]) -> np.ndarray:
    """Owned W-dofs (local indices) of the state component ``sub`` on the edge ``tag``."""
    facets = model.strip.facet_tags.find(tag)
    return owned_subspace_dofs(model.W, sub, model.mesh.topology.dim - 1, facets)


def edge_conditions(model: NaghdiShell, tag: int):
    """Dirichlet conditions on the whole state (u and theta) of the edge ``tag``: (values, bcs)."""
    facets = model.strip.facet_tags.find(tag)
    conditions = [facet_condition(model, (i,), facets) for i in (0, 1)]
    return [value for value, _ in conditions], [bc for _, bc in conditions]


@dataclass
class EdgeMotion:
    """Dirichlet conditions holding the edge ``tag`` to a rigid motion of the reference edge.

    The motion is a rotation by ``angle`` about the line through ``axis_point`` along ``axis``
    followed by a translation; :meth:`set` updates it between load steps. With angle 0 and no
    translation the edge is clamped.
    """

    model: NaghdiShell
    tag: int
    axis: np.ndarray
    axis_point: np.ndarray

    def __post_init__(self):
        self.values, self.bcs = edge_conditions(self.model, self.tag)
        self.angle = 0.0

    def set(self, angle: float, translation=(0.0, 0.0, 0.0)) -> None:
        """Prescribe the rigid motion: rotation ``angle`` [rad], then ``translation`` [m]."""
        geom = self.model.strip.geometry
        Q = rotation_matrix(self.axis, angle)
        c = np.asarray(self.axis_point, dtype=float).reshape(3, 1)
        t = np.asarray(translation, dtype=float).reshape(3, 1)

        def displacement(x):
            X = geom.phi0(x)
            return Q @ (X - c) + c + t - X

        def angles(x):
            return self.model.angles_of(Q @ geom.frame(x)[2], x, rotation_near=angle)

        self.values[0].interpolate(displacement)
        self.values[1].interpolate(angles)
        self.angle = angle


def clamp(model: NaghdiShell, tag: int) -> EdgeMotion:
    """A clamped edge: zero displacement and rotation."""
    return EdgeMotion(model, tag, axis=np.array([0.0, 1.0, 0.0]), axis_point=np.zeros(3))


def hinge(model: NaghdiShell, tag: int) -> list:
    """A hinged edge: zero displacement, the director free to turn (a shell's simple support
    held in place along and across the edge)."""
    _, bc = facet_condition(model, (0,), model.strip.facet_tags.find(tag))
    return [bc]


@dataclass
class RigidSection:
    """An edge turned rigidly by a prescribed rotation while free to translate.

    The director is prescribed (Dirichlet, the rotated reference normal) and a penalty
    stiffness/2 |d(u - u_Q)/d xi_2|^2 on the edge makes the edge's displacement differ from the
    rigid rotation u_Q = (Q - I)(phi0 - c) by a constant only, i.e. by a translation: the edge
    moves as a rigid body with the rotation Q and an unknown translation, so the loading is a
    pure moment about ``axis``. u_Q is the finite element interpolant of the rigid rotation, so
    that the constraint is met exactly by the discrete field (comparing with the exact rotated
    arc would charge the interpolation error at the penalty stiffness). The penalty energy is
    part of the total energy, whose derivative along the path is the moment.
    """

    model: NaghdiShell
    tag: int
    axis: np.ndarray
    stiffness: float

    def __post_init__(self):
        import ufl

        m = self.model
        self.theta, bc = facet_condition(m, (1,), m.strip.facet_tags.find(self.tag))
        self.bcs = [bc]
        V0, _ = m.W.sub(0).collapse()
        self.rigid_displacement = dolfinx.fem.Function(V0)
        mismatch = ufl.grad(m.u - self.rigid_displacement)[:, 1]
        self.energy = 0.5 * self.stiffness * ufl.dot(mismatch, mismatch) * m.ds(self.tag)
        self.angle = 0.0

    def set(self, angle: float) -> None:
        geom = self.model.strip.geometry
        Q = rotation_matrix(self.axis, angle)

        def angles(x):
            return self.model.angles_of(Q @ geom.frame(x)[2], x, rotation_near=angle)

        self.theta.interpolate(angles)
        self.rigid_displacement.interpolate(lambda x: (Q - np.eye(3)) @ geom.phi0(x))
        self.angle = angle
