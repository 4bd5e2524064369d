"""The hybrid's shell window on the hub in coiling (:class:`WindowOnHub`): a stretch of the
Naghdi shell anywhere along the tape, touching the hub and the turns beneath on the spiral, its
root attached to the hub when it starts at the root, the free end's guide and pull when it ends
there (unless released: a deploying tape's), and the coiling's predictors for the material in it."""

from __future__ import annotations

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.core import jit
from tapecoil.core.dofs import assemble_into, global_scalar, owned_subspace_dofs
from tapecoil.geometry.meshes import FREE_END, ROOT, MeshResolution
from tapecoil.geometry.sections import CircularArcSection
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.hub.attachment import HubRoot
from tapecoil.hub.contact import CoilContact, ContactSettings
from tapecoil.hub.frame import HubFrame
from tapecoil.measures.section_forces import SectionForces
from tapecoil.models.edges import facet_condition, owned_edge_dofs
from tapecoil.models.materials import shell_material
from tapecoil.models.nodes import Nodes
from tapecoil.models.problem import ShellProblem
from tapecoil.phases.coiling import GUIDE_COMPONENTS
from tapecoil.phases.predictors import AlongTape, turn_wound, wound_length

__all__ = ["WindowOnHub"]


class WindowOnHub(ShellProblem):
    """The hybrid's shell window from ``start`` [m] along the tape, ``length`` [m] long, on the
    hub of ``frame``: the contact of its face with the hub and the turns beneath
    (:class:`CoilContact`, the spiral), the root attached to the hub when the window starts at
    the root, the free end's guide and pull ``pull`` [N] (by default ``coiling.tension``) when it
    ends at the free end, unless
    ``released`` (the end then free, as a deploying tape's: :class:`~tapecoil.phases.release.EndHold`
    lets it go, the window standing in for the tape there).

    The load parameter is the hub angle [rad], or the root's flattening while ``flattening``.
    """

    def __init__(
        self,
        config: Config,
        start: float,
        length: float,
        element: float,
        frame: HubFrame,
        contact: ContactSettings,
        *,
        shift: bool = False,
        released: bool = False,
        pull: float | None = None,
        comm=MPI.COMM_WORLD,
        name: str = "window",
    ):
        tp = config.tape
        self.config, self.comm, self.element_length = config, comm, element
        across = MeshResolution.from_config(config.mesh, tp.L).across
        super().__init__(
            StripGeometry(tp.R, tp.b, length, start=start),
            MeshResolution(across, max(1, round(length / element))),
            shell_material(config),
            comm=comm,
            name=name,
            director_frame="global",
        )
        model = self.model
        self.frame = frame
        self.contact = CoilContact(
            model,
            frame,
            contact.penalty,
            contact.max_turns,
            contact.ramp_width,
            contact.smoothing,
            contact.turns,
        )
        self.flattening = False
        self._along = AlongTape(self.contact.nodes, comm) if shift else None
        self.root = None
        if start <= 1e-9 * tp.L:
            self.root = HubRoot(model, ROOT, frame, CircularArcSection.from_tape(tp))
            self.bcs += self.root.bcs
            self.contact.reset()
        energy = model.strain_energy + self.contact.energy
        # the strain and contact energy (an end hold's internal forces are its derivative)
        self.energy = energy
        if start + length >= tp.L * (1 - 1e-9) and not released:
            free_end = self.strip.facet_tags.find(FREE_END)
            self.bcs += [facet_condition(model, sub, free_end)[1] for sub in GUIDE_COMPONENTS]
            # T spread evenly over the free end's arc, as the full shell's pull
            pull = config.coiling.tension if pull is None else pull
            energy = energy - pull * model.u[0] / tp.b * model.ds(FREE_END)
        self._energy = energy
        self._strain_form = self._root_form = self._sections = None  # made when first read

    def forms(self) -> tuple:
        F = ufl.derivative(self._energy, self.model.q, self.model.dq)
        return F, self.model.jacobian_form(F)

    def set_load(self, value: float) -> None:
        super().set_load(value)
        if self.flattening:
            self.root.set(value, 0.0)
            return
        if self.root is not None:
            self.root.set(1.0, value)
        self.contact.turn(value)

    def commit(self, load: float) -> None:
        if not self.flattening:
            self.contact.update(load)

    def state_fields(self) -> dict:
        """The shell's state and the winding angles of its nodes, as cell fields (a restart's)."""
        from tapecoil.core.cell_state import function_field

        return {"q": function_field(self.model.q), "winding": function_field(self.contact.psi)}

    def state_values(self) -> dict:
        return {"hub_angle": self.contact.hub_angle}

    def set_state_values(self, values: dict) -> None:
        """Put back :meth:`state_values` (after the fields): the contact's hub angle; the loads
        are the caller's to set."""
        self.contact.hub_angle = float(values["hub_angle"])

    def edge_dofs(self, tag: int, sub: tuple[int, ...]) -> np.ndarray:
        """Owned W-dofs (local indices) of the state component ``sub`` on the edge ``tag``."""
        return owned_edge_dofs(self.model, tag, sub)

    def section_forces(self) -> dict:
        """The window's section forces along the tape
        (:class:`~tapecoil.measures.section_forces.SectionForces`; collective)."""
        if self._sections is None:
            self._sections = SectionForces(self.model, Nodes(self.model), self.strip.mesh.comm)
        return self._sections()

    def strain_energy(self) -> float:
        """The window's strain energy [J] (collective)."""
        if self._strain_form is None:
            self._strain_form = jit.form(self.model.strain_energy)
        return global_scalar(self._strain_form, self.strip.mesh.comm)

    def root_force(self) -> np.ndarray:
        """The internal force [N] on the window's root edge, dE/du summed over its dofs
        (collective)."""
        model = self.model
        if self._root_form is None:
            self._root_form = jit.form(ufl.derivative(self._energy, model.q, model.dq))
            self._root_vector = dolfinx.fem.Function(model.W)
            facets = self.strip.facet_tags.find(ROOT)
            self._root_dofs = [owned_subspace_dofs(model.W, (0, i), 1, facets) for i in range(3)]
        f = assemble_into(self._root_vector, self._root_form)
        local = np.array([f[dofs].sum() for dofs in self._root_dofs])
        return self.strip.mesh.comm.allreduce(local, op=MPI.SUM)

    def predict(self, load_from: float, load_to: float) -> None:
        """The material already on the coil turns with the hub, as the beam's does; with
        ``shift``, the rest takes the state of the material the wound length behind it, as the
        full shell's coiling predicts (:class:`~tapecoil.phases.predictors.CoilingPredictor`),
        where that material is in the window."""
        if self.flattening:
            return
        q = self.model.q.x.array
        current = q.copy()
        c = self.contact
        nodes = c.nodes
        if self._along is not None:
            ds = wound_length(c, load_from, load_to)
            shifted = self._along.values_at(current, -ds)
            start = self.surface.xi_range[0][0]
            inside = nodes.xi[0] - ds >= start - 1e-9 * (1.0 + start)
            q[nodes.u_dofs[inside]] = shifted[inside, :3] - np.array([ds, 0.0, 0.0])
            q[nodes.theta_dofs[inside]] = shifted[inside, 3:]
        turn_wound(q, current, nodes, c.psi.x.array, self.frame, load_from, load_to - load_from)
