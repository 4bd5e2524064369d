"""The tape on its hub: the strip, the shell, the hub, the root attachment and the contact.

What every phase of a tape spring's life on a hub shares, and nothing a single phase adds: the
coiling adds the guide, the pull, its solver and predictor; the deployment the inertia, the
release and its time stepping. A checkpoint of any phase holds this state (the shell's state and
the winding angles), so a phase starts from another's checkpoint by reading this alone, without
building the other phase's forms or solver. The turns' contact with each other is
:mod:`~tapecoil.phases.turn_contact`'s, the centre-line measures :mod:`~tapecoil.measures.centre_line`'s.
"""

from __future__ import annotations

from pathlib import Path

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.contact.surface import ShellSurface
from tapecoil.contact.term import SOLVER_OPTIONS
from tapecoil.core import checkpoint, jit
from tapecoil.core.cell_state import function_field, gather_fields, scatter_fields
from tapecoil.core.checkpoint import state_parts
from tapecoil.core.dofs import assemble_into, global_scalar
from tapecoil.geometry.meshes import ROOT, MeshResolution, StripMesh, create_strip_mesh
from tapecoil.geometry.sections import CircularArcSection
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.hub.attachment import HubRoot
from tapecoil.hub.contact import CoilContact, ContactSettings
from tapecoil.hub.frame import HubFrame
from tapecoil.hub.friction import HubFriction
from tapecoil.measures import centre_line as centre
from tapecoil.models.edges import owned_edge_dofs
from tapecoil.models.shell import NaghdiShell, shell_material
from tapecoil.phases.turn_contact import TurnContact


class TapeOnHub:
    """The tape's strip and shell, the hub (:class:`HubFrame`), the root and the contact.

    ``strip``: an existing strip mesh (a checkpoint's); otherwise one is built from ``config``
    (or ``resolution``).
    """

    def __init__(
        self,
        config: Config,
        comm=MPI.COMM_WORLD,
        resolution: MeshResolution | None = None,
        strip: StripMesh | None = None,
    ):
        self.config = config
        self.comm = comm
        tp, r_hub = config.tape, config.hub.radius
        self.r_hub = r_hub
        if strip is None:
            geom = StripGeometry(tp.R, tp.b, tp.L)
            strip = create_strip_mesh(comm, geom, resolution or MeshResolution.from_config(config.mesh, tp.L))
        self.strip = strip
        self.element_length = tp.L / strip.resolution.along
        self.model = model = NaghdiShell(strip, shell_material(config), director_frame="global")
        self.frame = HubFrame(r_hub, tp.h, config.coiling.sense)
        self.root = HubRoot(model, ROOT, self.frame, CircularArcSection.from_tape(tp))

        cs = ContactSettings.from_config(config, self.element_length)
        self.penalty = cs.penalty
        self.contact = CoilContact(
            model, self.frame, cs.penalty, cs.max_turns, cs.ramp_width, cs.smoothing, cs.turns
        )
        self.contact.reset()
        # Coulomb friction on the hub (contact.hub_friction): a force of no energy, its anchors
        # on the hub where the tape's face is now
        mu = config.contact.hub_friction
        self.friction = HubFriction(self.contact, mu) if mu > 0 else None
        if self.friction is not None:
            self.friction.reset()
        self.turns = None
        if cs.turns == "surface":
            self.turns = TurnContact(
                ShellSurface(model, self.contact.nodes), self.frame, tp.h, cs.penalty, cs.smoothing, cs.buffer
            )
        # strain + contact energy as forms (the turns' real contact is assembled on its own:
        # add_self_contact_force)
        self.energy = model.strain_energy + self.contact.energy
        parts = [
            ("membrane", model.energy_membrane),
            ("bending", model.energy_bending),
            ("shear", model.energy_shear),
            ("contact_hub", self.contact.energy_hub),
        ]
        if self.contact.energy_coil is not None:
            parts.append(("contact_coil", self.contact.energy_coil))
        self.forms = {name: jit.form(form) for name, form in parts}
        self._internal: dict[int, tuple] = {}
        self._root_dofs = None

    def edge_dofs(self, tag: int, sub: tuple[int, ...]) -> np.ndarray:
        """Owned W-dofs (local indices) of the state component ``sub`` on the edge ``tag``."""
        return owned_edge_dofs(self.model, tag, sub)

    def energies(self) -> dict[str, float]:
        comm = self.model.mesh.comm
        out = {name: global_scalar(self.forms[name], comm) for name in ("membrane", "bending", "shear")}
        out.update(self._contact_parts())
        out["strain"] = out["membrane"] + out["bending"] + out["shear"]
        out["contact"] = out["contact_hub"] + out["contact_coil"]
        # what the hub's friction holds in its sticking springs, and what its slip has dissipated
        friction = self.friction
        out["friction"] = friction.spring_energy() if friction is not None else 0.0
        out["friction_dissipated"] = friction.dissipated if friction is not None else 0.0
        return out

    def _contact_parts(self) -> dict[str, float]:
        comm = self.model.mesh.comm
        coil = (
            self.turns.energy() if self.turns is not None else global_scalar(self.forms["contact_coil"], comm)
        )
        return {"contact_hub": global_scalar(self.forms["contact_hub"], comm), "contact_coil": coil}

    def hub_contact_energy(self) -> float:
        """The penalty energy against the hub (with its fairing, in the surface mode) [J]
        (collective)."""
        return global_scalar(self.forms["contact_hub"], self.model.mesh.comm)

    def contact_energy(self) -> float:
        """The penalty energy of the hub's and the turns' contact [J] (collective)."""
        parts = self._contact_parts()
        return parts["contact_hub"] + parts["contact_coil"]

    def section_forces(self) -> dict:
        """The axial force across every section of the tape
        (:class:`~tapecoil.measures.section_forces.SectionForces`; collective)."""
        if getattr(self, "_sections", None) is None:
            from tapecoil.measures.section_forces import SectionForces

            self._sections = SectionForces(self.model, self.contact.nodes, self.comm)
        return self._sections()

    # the phases and the measures read the centre line as the tape's
    centre_nodes = centre.centre_nodes
    centre_line = centre.centre_line
    coil_geometry = centre.coil_geometry

    def max_penetration(self) -> float:
        """Largest penetration into the hub or of the tape into itself [m] (>= 0, collective)."""
        local = self.contact.nodal_penetration()
        hub = max(self.comm.allreduce(float(local.max()) if local.size else 0.0, op=MPI.MAX), 0.0)
        return hub if self.turns is None else max(hub, self.turns.max_penetration())

    def penetration_refusal(self) -> str | None:
        """Why the current state is refused, if the tape has gone deeper into the hub or into
        itself than ``contact.stop_penetration`` h: the penalty no longer keeps the faces apart
        (collective; None when it holds). The continuation cuts such a step back, and stops
        with this message and the last accepted state when no shorter step passes."""
        h, limit = self.config.tape.h, self.config.contact.stop_penetration
        penetration = self.max_penetration()
        if penetration <= limit * h:
            return None
        return (
            f"the tape penetrates the hub or its own turns by {penetration / h:.4f} h, more than "
            f"contact.stop_penetration = {limit:g} h: the contact no longer keeps the faces apart "
            "(a stiffer contact.penalty_scale or a finer mesh)"
        )

    def internal_force(self, energy=None) -> np.ndarray:
        """The internal force dE/dq at the current state, local array of W (collective): E the
        tape's strain and hub contact (``energy``: a phase's own, with its obstacles), plus the
        hub's friction and the turns' real contact. What the root's attachment and the free
        end's guide balance."""
        energy = self.energy if energy is None else energy
        cached = self._internal.get(id(energy))
        if cached is None:  # the energy is kept with its form, so that its id stays its own
            force = ufl.derivative(energy, self.model.q, self.model.dq)
            if self.friction is not None:
                force = force + self.friction.residual
            form = jit.form(force)
            cached = self._internal[id(energy)] = (energy, form, dolfinx.fem.Function(self.model.W))
        _, form, vector = cached
        assemble_into(vector, form)
        self.add_self_contact_force(vector)
        return vector.x.array

    def root_force(self, force: np.ndarray) -> np.ndarray:
        """The sum of ``force`` (a local array of W) over the root edge's displacements, a
        vector in the global frame [N] (collective)."""
        if self._root_dofs is None:
            self._root_dofs = [self.edge_dofs(ROOT, (0, i)) for i in range(3)]
        local = np.array([float(force[dofs].sum()) for dofs in self._root_dofs])
        return self.comm.allreduce(local, op=MPI.SUM)

    def add_self_contact_force(self, force: dolfinx.fem.Function) -> None:
        """Add the force of the turns' real contact dE/dq at the current state to ``force``
        (collective; nothing with the spiral obstacle, whose force is in ``energy``)."""
        if self.turns is not None:
            self.turns.add_force(force)

    def accept_state(self) -> None:
        """After a converged step: the turns' real contact reads its sides from this state, and
        the hub's friction moves its anchors by the step's slip (on a state already accepted,
        a restored one, both leave things as they are)."""
        if self.turns is not None:
            self.turns.accept()
        if self.friction is not None:
            self.friction.commit()

    def friction_residual(self):
        """The hub friction's virtual work (UFL form; None without friction): a phase's
        residual adds it to the derivative of its energy."""
        return None if self.friction is None else self.friction.residual

    def solver_options(self) -> dict:
        """PETSc options a solver with this tape's contact terms needs (names without prefix):
        friction, like the turns' real contact, makes the Jacobian unsymmetric (LU)."""
        if self.turns is not None:
            return dict(SOLVER_OPTIONS)
        return {} if self.friction is None else {"pc_type": "lu"}

    def contact_terms(self, q, bcs, weight: float = 1.0, previous=None) -> list:
        """The solver terms of the turns' real contact (:meth:`TurnContact.term`), if any."""
        return [] if self.turns is None else [self.turns.shell_term(q, bcs, weight, previous)]

    # -- checkpoint -------------------------------------------------------------------------
    def checkpoint_functions(self) -> dict:
        """The functions of this state in a checkpoint: u, theta and the winding angles."""
        return {**state_parts(self.model.q, ""), "winding_angle": self.contact.psi}

    def write_checkpoint(
        self, path: str | Path, meta: dict, extra: dict | None = None, tables: dict | None = None
    ) -> None:
        """Mesh, tags, state and winding angles (and a phase's ``extra`` functions and ``tables``,
        :func:`~tapecoil.core.checkpoint.write_checkpoint`) with ``meta``.

        adios4dolfinx (ADIOS2 BP) for the mesh and the functions; ``meta`` (the hub angle and
        each phase's restart state) as JSON beside it. Written atomically
        (:mod:`tapecoil.core.checkpoint`).
        """
        functions = {**self.checkpoint_functions(), **(extra or {})}
        res = self.strip.resolution
        meta = {**meta, "resolution": {"across": res.across, "along": res.along, "grading": res.grading}}
        if self.friction is not None:
            # the anchors live at quadrature points, which adios4dolfinx does not write: cell by
            # cell in the order it writes the mesh, so that the mesh read back takes them back
            field = {"friction_anchor": function_field(self.friction.anchor)}
            tables = {**(tables or {}), **gather_fields(field, self.comm, numbering="global")}
            meta["friction_dissipated"] = self.friction.dissipated
        tags = {"facets": self.strip.facet_tags, "cells": self.strip.cell_tags}
        checkpoint.write_checkpoint(path, self.strip.mesh, tags, functions, meta, self.comm, tables)

    @classmethod
    def read_checkpoint(cls, path: str | Path, config: Config, comm=MPI.COMM_WORLD) -> tuple[TapeOnHub, dict]:
        """The tape in the state of a checkpoint of any phase (any rank count), and its meta.

        The root is attached at the checkpoint's hub angle, flattened.
        """
        meta = checkpoint.read_meta(path)
        tp = config.tape
        mesh, tags = checkpoint.read_mesh(path, comm, ("facets", "cells"))
        resolution = MeshResolution(**meta["resolution"])
        strip = StripMesh(mesh, tags["cells"], tags["facets"], StripGeometry(tp.R, tp.b, tp.L), resolution)
        tape = cls(config, comm, strip=strip)
        parts = checkpoint.empty_state_parts(tape.model.W, "")
        checkpoint.read_functions(path, {**parts, "winding_angle": tape.contact.psi})
        checkpoint.set_state(tape.model.q, parts, "")
        tape.accept_state()
        if tape.friction is not None:
            # the checkpoint's anchors; a coil wound without friction starts it from here
            tables = checkpoint.read_tables(path) or {}
            if "friction_anchor" in tables:
                scatter_fields({"friction_anchor": function_field(tape.friction.anchor)}, tables)
                tape.friction.dissipated = meta.get("friction_dissipated", 0.0)
            else:
                tape.friction.reset()
        tape.contact.hub_angle = meta["hub_angle"]
        tape.root.set(1.0, meta["hub_angle"])
        tape.contact.turn(meta["hub_angle"])
        return tape, meta
