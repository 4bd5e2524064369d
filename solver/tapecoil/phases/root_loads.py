"""The loads the tape puts on the hub through its root attachment: force, moment, torque.

What the designer of a hub and of its interface with the spacecraft needs: the force [N] and
moment [N m] the tape exerts on the hub at the root, through deployment. They are the
attachment's reaction, read from the equation of motion at the converged state t_{n+1}
(:meth:`~tapecoil.phases.deployment_forms.DeploymentForms.reaction`: inertia plus internal and
contact forces), whose residual on the root's dofs is what the attachment supplies to the tape;
the hub carries its opposite. The hub contact's pressure passes through the axis and adds no
torque about it, but it does add force, and its friction (contact.hub_friction) adds both; the
root loads are the attachment's alone.

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

from tapecoil.core import jit
from tapecoil.core.dofs import assemble_into, owned_constrained_dofs
from tapecoil.core.rotation import rotation_matrix

COMPONENTS = ("x", "y", "z")


def shell_root_reaction(f, q, nodes, root, angles_of, axis_point, eps: float = 1e-6) -> np.ndarray:
    """The attachment's force [N] and moment [N m] about ``axis_point`` on a shell's root, from
    the reaction ``f`` (a dof array: the equation of motion's residual) at the state ``q``, over
    the ``root`` nodes of ``nodes`` (:class:`~tapecoil.models.nodes.Nodes`) this rank owns; the
    director angles of turned directors by ``angles_of(d, xi, theta1)`` (rank-local, (6,))."""
    f_u = f[nodes.u_dofs[root]]  # (n, 3): the attachment's force on the tape at each node
    f_theta = f[nodes.theta_dofs[root]]
    x = nodes.positions(q)[:, root]
    d = nodes.directors(q)[:, root]
    xi = nodes.xi[:, root]
    theta1 = q[nodes.theta_dofs[root, 1]]
    c = np.asarray(axis_point, dtype=float)[:, None]
    moment = np.zeros(3)
    for k, e in enumerate(np.eye(3) if len(root) else ()):  # a rank may hold none of the root
        lever = np.cross(e, (x - c).T)  # (n, 3): the rate of x in a rotation about e
        turned = [angles_of(rotation_matrix(e, s * eps) @ d, xi, theta1) for s in (1, -1)]
        rate = (turned[0] - turned[1]).T / (2 * eps)
        moment[k] = np.sum(f_u * lever) + np.sum(f_theta * rate)
    return np.concatenate([f_u.sum(axis=0), moment])


def beam_root_reaction(f, x, u_dofs, theta_dofs, axis_point) -> np.ndarray:
    """The attachment's force [N] and moment [N m] about ``axis_point`` on a beam's root nodes at
    ``x`` (n, 3) [m], from the reaction ``f`` (a dof array) on their displacement and rotation
    dofs ``u_dofs``, ``theta_dofs`` (n, 3), the rotation's being the spatial rotation vector of a
    step at its start (zero: its residual is the moment itself; rank-local, (6,))."""
    f_u, f_theta = f[u_dofs].reshape(-1, 3), f[theta_dofs].reshape(-1, 3)
    arm = np.asarray(x, dtype=float).reshape(-1, 3) - np.asarray(axis_point, dtype=float)
    return np.concatenate([f_u.sum(axis=0), f_theta.sum(axis=0) + np.cross(arm, f_u).sum(axis=0)])


def loads_on_hub(local: np.ndarray, comm, axis) -> dict[str, float]:
    """The root's loads on the hub from the ranks' shares ``local`` of the attachment's force and
    moment on the tape (collective): their opposite, and the torque about the hub's ``axis``."""
    total = -comm.allreduce(np.asarray(local, dtype=float), op=MPI.SUM)
    out = {f"root_force_{a}": float(v) for a, v in zip(COMPONENTS, total[:3], strict=True)}
    out.update({f"root_moment_{a}": float(v) for a, v in zip(COMPONENTS, total[3:], strict=True)})
    out["root_torque"] = float(np.dot(total[3:], axis))
    return out


class RootLoads:
    """The root's loads on the hub of a :class:`~tapecoil.phases.deployment.DeploymentProblem`;
    call it after a converged step (collective)."""

    def __init__(self, model, eps: float = 1e-6):
        self.m, self.eps = model, eps
        tape = model.tape
        # the root's own share of the weight is the attachment's too
        self.form = jit.form(model.forms.reaction() - model.weight)
        self.reaction = dolfinx.fem.Function(model.model.W)
        nodes = tape.contact.nodes
        held = owned_constrained_dofs(model.model.W, model.bcs)
        n_owned = nodes.space.dofmap.index_map.size_local
        # the root's nodes this rank owns: those whose displacement the attachment holds
        self.root = np.flatnonzero(np.isin(nodes.u_dofs[:n_owned, 0], held))
        self.nodes = nodes
        self.frame = tape.frame

    def __call__(self) -> dict[str, float]:
        m = self.m
        assemble_into(self.reaction, self.form)
        m.tape.add_self_contact_force(self.reaction)
        local = shell_root_reaction(
            self.reaction.x.array,
            m.model.q.x.array,
            self.nodes,
            self.root,
            m.model.angles_of,
            self.frame.axis_point,
            self.eps,
        )
        return loads_on_hub(local, m.comm, self.frame.axis)


class HybridRootLoads:
    """The root's loads on the hub of the shell-beam ``hybrid`` on the hub of ``frame``: the
    reaction of the beam's clamped root node while the shell window starts past the root, of the
    window's attached root edge once it starts there, each the residual ``shell_form`` or
    ``beam_form`` on the held dofs at the converged state, as the full shell's
    (:class:`RootLoads`). :meth:`in_time` reads the equation of motion, :meth:`at_rest` the
    equilibrium of the quasi-static hybrid; call it after a converged, committed step
    (collective)."""

    def __init__(self, hybrid, frame, shell_form, beam_form, eps: float = 1e-6):
        shell, beam = hybrid.shell, hybrid.beam
        self.frame, self.eps, self.comm = frame, eps, shell.comm
        self.shell = shell.root is not None
        if self.shell:  # the window's own root, attached to the hub
            model = shell.model
            self.model, self.nodes = model, shell.contact.nodes
            held = owned_constrained_dofs(model.W, shell.root.bcs)
            n_owned = self.nodes.space.dofmap.index_map.size_local
            self.root = np.flatnonzero(np.isin(self.nodes.u_dofs[:n_owned, 0], held))
        else:  # the beam's root node, clamped to the hub
            model = beam.model
            self.model = model
            held = owned_constrained_dofs(model.W, beam.bcs)
            self.root = np.flatnonzero(np.isin(model.node_u_dofs[:, 0], held))
        self.form = jit.form(shell_form if self.shell else beam_form)
        self.reaction = dolfinx.fem.Function(self.model.W)

    @classmethod
    def in_time(cls, motion, frame, eps: float = 1e-6) -> HybridRootLoads:
        """Of a :class:`~tapecoil.phases.hybrid_motion.HybridMotion`'s hybrid: its equation of
        motion at t_{n+1}, once the motion has committed the step."""
        shell = motion.hybrid.shell
        shell_form = motion.shell_forms.inertia_at_end() + shell.forms()[0] - motion.shell_weight
        return cls(motion.hybrid, frame, shell_form, motion.beam.reaction_form, eps)

    @classmethod
    def at_rest(cls, hybrid, frame, eps: float = 1e-6) -> HybridRootLoads:
        """Of a quasi-static hybrid (coiling, a driven hub's payout): its energy's gradient."""
        return cls(hybrid, frame, hybrid.shell.forms()[0], hybrid.beam.forms()[0], eps)

    def __call__(self) -> dict[str, float]:
        assemble_into(self.reaction, self.form)
        f, q = self.reaction.x.array, self.model.q.x.array
        c = self.frame.axis_point
        if self.shell:
            local = shell_root_reaction(f, q, self.nodes, self.root, self.model.angles_of, c, self.eps)
        else:
            m, root = self.model, self.root
            x = m.node_points[root] + q[m.node_u_dofs[root]]
            local = beam_root_reaction(f, x, m.node_u_dofs[root], m.node_theta_dofs[root], c)
        return loads_on_hub(local, self.comm, self.frame.axis)
