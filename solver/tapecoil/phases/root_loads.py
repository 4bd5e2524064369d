"""The loads the tape puts on the hub through its root attachment: force, moment, torque.

What the designer of a hub and of its interface with the spacecraft needs: the force [N] and
moment [N m] the tape exerts on the hub at the root, through deployment. They are the
attachment's reaction, read from the equation of motion at the converged state t_{n+1}
(:meth:`~tapecoil.phases.deployment_forms.DeploymentForms.reaction`: inertia plus internal and
contact forces), whose residual on the root's dofs is what the attachment supplies to the tape;
the hub carries its opposite. The hub contact adds no torque about the hub's axis (it is
frictionless and its pressure passes through the axis), but it does add force; the root loads are
the attachment's alone.

Force: the sum over the root's displacement dofs. Moment about the hub's axis point c, about each
axis e: the virtual work of the reaction in a rigid rotation of the root about e,
sum f . (e x (x - c)) over the displacement dofs plus sum F_theta . dtheta over the director
angles, dtheta the rate of the angles of the root's directors rotated about e (central
differences). Torque: the moment's component along the hub's axis, positive in the coiling
sense.
"""

from __future__ import annotations

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.core.dofs import assemble_into, owned_constrained_dofs
from tapecoil.core.rotation import rotation_matrix

COMPONENTS = ("x", "y", "z")


class RootLoads:
    """The root's loads on the hub of a :class:`~tapecoil.phases.deployment.DeploymentModel`;
    call it after a converged step (collective)."""

    def __init__(self, model, eps: float = 1e-6):
        self.m, self.eps = model, eps
        tape = model.tape
        self.form = dolfinx.fem.form(model.forms.reaction())
        self.reaction = dolfinx.fem.Function(model.model.W)
        nodes = tape.contact.nodes
        held = owned_constrained_dofs(model.model.W, model.bcs)
        n_owned = nodes.space.dofmap.index_map.size_local
        # the root's nodes this rank owns: those whose displacement the attachment holds
        at_root = np.isin(nodes.u_dofs[:n_owned, 0], held)
        self.root = np.flatnonzero(at_root)
        self.nodes = nodes
        self.frame = tape.frame

    def __call__(self) -> dict[str, float]:
        m = self.m
        assemble_into(self.reaction, self.form)
        m.tape.add_self_contact_force(self.reaction)
        f, q, nodes, root = self.reaction.x.array, m.model.q.x.array, self.nodes, self.root
        f_u = f[nodes.u_dofs[root]]  # (n, 3): the attachment's force on the tape at each node
        f_theta = f[nodes.theta_dofs[root]]
        x = nodes.positions(q)[:, root]
        d = nodes.directors(q)[:, root]
        xi = nodes.xi[:, root]
        theta1 = q[nodes.theta_dofs[root, 1]]
        c = self.frame.axis_point[:, None]
        moment = np.zeros(3)
        for k, e in enumerate(np.eye(3) if len(root) else ()):  # a rank may hold none of the root
            lever = np.cross(e, (x - c).T)  # (n, 3): the rate of x in a rotation about e
            turned = [m.model.angles_of(rotation_matrix(e, s * self.eps) @ d, xi, theta1) for s in (1, -1)]
            rate = (turned[0] - turned[1]).T / (2 * self.eps)
            moment[k] = np.sum(f_u * lever) + np.sum(f_theta * rate)
        local = np.concatenate([f_u.sum(axis=0), moment])
        total = -m.comm.allreduce(local, op=MPI.SUM)  # on the hub: the opposite of on the tape
        out = {f"root_force_{a}": float(v) for a, v in zip(COMPONENTS, total[:3], strict=True)}
        out.update({f"root_moment_{a}": float(v) for a, v in zip(COMPONENTS, total[3:], strict=True)})
        out["root_torque"] = float(np.dot(total[3:], self.frame.axis))
        return out
