"""The tape on its hub: the strip, the shell, the hub, the root attachment and the contact.

What every phase of a tape spring's life on a hub shares, and nothing a single phase adds: the
coiling adds the guide, the pull, its solver and predictor; the deployment the inertia, the
release and its time stepping. A checkpoint of any phase holds this state (the shell's state and
the winding angles), so a phase starts from another's checkpoint by reading this alone, without
building the other phase's forms or solver.
"""

from __future__ import annotations

import math
from pathlib import Path

import dolfinx
import numpy as np
from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.contact.self_contact import PairsAtState, SelfContact, SelfContactTerm
from tapecoil.core import checkpoint
from tapecoil.core.checkpoint import state_parts
from tapecoil.core.dofs import global_scalar, owned_subspace_dofs
from tapecoil.core.stepping import ContinuationError
from tapecoil.geometry.meshes import ROOT, MeshResolution, StripMesh, create_strip_mesh
from tapecoil.geometry.sections import CircularArcSection
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.hub.attachment import HubRoot
from tapecoil.hub.contact import CoilContact, default_penalty
from tapecoil.hub.frame import HubFrame
from tapecoil.models.shell import NaghdiShell, ShellMaterial


def check_penetration(penetration: float, config, load: float, where: str) -> None:
    """Stop (ContinuationError at ``load``) if the tape has gone deeper into the hub or itself
    than ``contact.stop_penetration`` h: the penalty no longer keeps the faces apart."""
    h, limit = config.tape.h, config.contact.stop_penetration
    if penetration > limit * h:
        raise ContinuationError(
            f"at {where} the tape penetrates the hub or its own turns by {penetration / h:.3g} h, more "
            f"than contact.stop_penetration = {limit:g} h: the contact no longer keeps the faces apart "
            "(a stiffer contact.penalty_scale or a finer mesh); the state saved is this step's",
            load,
        )


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
        self.model = model = NaghdiShell(strip, ShellMaterial(tp.E, tp.nu, tp.h), director_frame="global")
        self.frame = HubFrame(r_hub, tp.h, config.coiling.sense)
        self.root = HubRoot(model, ROOT, self.frame, CircularArcSection.from_tape(tp))

        cc = config.contact
        self.penalty = cc.penalty or cc.penalty_scale * default_penalty(tp.E, tp.h, self.element_length)
        max_turns = math.ceil((config.coiling.hub_angle + math.pi) / (2 * math.pi)) + 1
        # the climb over the root end spread over about two elements (at least 0.3 rad)
        ramp = max(2 * self.element_length / r_hub, 0.3)
        smoothing = cc.smoothing * tp.h
        self.contact = CoilContact(model, self.frame, self.penalty, max_turns, ramp, smoothing, cc.turns)
        self.contact.reset()
        self.self_contact = self.search = None
        if cc.turns == "surface":
            # the turns against each other: any part of the mid-surface against any other more
            # than a few search reaches away along the tape (its own neighbourhood)
            buffer = cc.search_margin * tp.h
            self.self_contact = SelfContact(
                model,
                self.contact.nodes,
                tp.h,
                self.penalty,
                smoothing,
                buffer,
                exclusion=4 * (tp.h + buffer),
                side_hint=self._coil_side,
            )
            self.search = self.self_contact.new_search()
            self._measured = PairsAtState(self.self_contact)
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
        self.forms = {name: dolfinx.fem.form(form) for name, form in parts}

    def _coil_side(self, node: np.ndarray, cell: np.ndarray) -> np.ndarray:
        """The side (+1, -1 along the surface's orientation) of cells their nodes lie on in a coil.

        Material wound later lies outside: a node farther along the tape than the cell is on
        the cell's outer side. The surface's orientation (xi_1 x xi_2, +z on the flat strip)
        points away from the hub in opposite-sense coiling and towards it in equal-sense, and a
        coil keeps it.
        """
        sc = self.self_contact
        outside = sc.material[node, 0] > sc.material[sc.cells[cell], 0].mean(axis=1)
        return self.frame.sign * np.where(outside, 1.0, -1.0)

    def edge_dofs(self, tag: int, sub: tuple[int, ...]) -> np.ndarray:
        """Owned W-dofs (local indices) of the state component ``sub`` on the edge ``tag``."""
        facets = self.strip.facet_tags.find(tag)
        return owned_subspace_dofs(self.model.W, sub, self.model.mesh.topology.dim - 1, facets)

    def energies(self) -> dict[str, float]:
        out = {name: global_scalar(form, self.model.mesh.comm) for name, form in self.forms.items()}
        if self.self_contact is not None:
            out["contact_coil"] = self.self_contact.energy(self._self_contact_pairs())
        out["strain"] = out["membrane"] + out["bending"] + out["shear"]
        out["contact"] = out["contact_hub"] + out["contact_coil"]
        return out

    def centre_nodes(self) -> np.ndarray:
        """Mask of this rank's owned nodes on the centre line (the line of xi_2 nearest 0; collective)."""
        nodes = self.contact.nodes
        distance = np.abs(nodes.xi[1, : nodes.space.dofmap.index_map.size_local])
        local_min = distance.min() if distance.size else np.inf
        return distance <= self.comm.allreduce(local_min, op=MPI.MIN) + 1e-9 * self.config.tape.b

    def centre_line(self) -> dict[str, np.ndarray]:
        """Centre-line nodes of the whole tape, sorted along it (collective, every rank).

        Columns: xi_1, winding angle psi, mid-surface distance from the hub axis.
        """
        nodes = self.contact.nodes
        n_owned = nodes.space.dofmap.index_map.size_local
        xi = nodes.xi[:, :n_owned]
        mask = self.centre_nodes()
        radius, _ = self.contact.polar(nodes.positions(self.model.q.x.array)[:, :n_owned])
        local = np.column_stack([xi[0][mask], self.contact.psi.x.array[:n_owned][mask], radius[mask]])
        rows = np.vstack(self.comm.allgather(local))
        rows = rows[np.argsort(rows[:, 0])]
        return {"xi1": rows[:, 0], "psi": rows[:, 1], "radius": rows[:, 2]}

    def coil_geometry(self, angle: float) -> dict[str, float]:
        """Coiled length and outer coil radius [m] (collective).

        The coiled length is the material length behind the tangent point, where the centre
        line's winding angle equals the hub angle. The outer radius is that of the outer face of
        the last turn half a turn behind the tangent point (mid-surface distance + h/2): at the
        tangent point itself the tape is already lifting off into the ploy region.
        """
        line = self.centre_line()
        psi, xi1, radius = line["psi"], line["xi1"], line["radius"]
        h = self.config.tape.h
        if angle <= psi[0]:
            return {"coiled_length": 0.0, "outer_radius": float(radius[0] + h / 2)}
        s = float(np.interp(angle, psi, xi1))
        probe = angle - math.pi if angle > math.pi else angle
        r = float(np.interp(probe, psi, radius))
        return {"coiled_length": s, "outer_radius": r + 0.5 * h}

    def max_penetration(self) -> float:
        """Largest penetration into the hub or of the tape into itself [m] (>= 0, collective)."""
        local = self.contact.nodal_penetration()
        hub = max(self.comm.allreduce(float(local.max()) if local.size else 0.0, op=MPI.MAX), 0.0)
        if self.self_contact is None:
            return hub
        return max(hub, self.self_contact.max_penetration(self._self_contact_pairs()))

    def add_self_contact_force(self, force: dolfinx.fem.Function) -> None:
        """Add the force of the turns' real contact dE/dq at the current state to ``force``
        (collective; nothing with the spiral obstacle, whose force is in ``energy``)."""
        if self.self_contact is not None:
            self.self_contact.add_force(force, self._self_contact_pairs())

    def _self_contact_pairs(self):
        """The turns' contact pairs at the current state, once per state for all the measures."""
        q = self.model.q.x.array
        return self._measured.get(q, lambda: self.self_contact.pairs(q, self.search))

    def accept_state(self) -> None:
        """After a converged step: the turns' real contact reads its sides from this state."""
        if self.self_contact is not None:
            self.self_contact.accept(self.model.q.x.array)

    def contact_terms(self, q, bcs, weight: float = 1.0, previous=None) -> list:
        """The solver terms of the turns' real contact (:class:`SelfContactTerm`), if any."""
        if self.self_contact is None:
            return []
        return [SelfContactTerm(self.self_contact, q, bcs, weight, previous)]

    # -- checkpoint -------------------------------------------------------------------------
    def checkpoint_functions(self) -> dict:
        """The functions of this state in a checkpoint: u, theta and the winding angles."""
        return {**state_parts(self.model.q, ""), "winding_angle": self.contact.psi}

    def write_checkpoint(self, path: str | Path, meta: dict, extra: dict | None = None) -> None:
        """Mesh, tags, state and winding angles (and a phase's ``extra`` functions) with ``meta``.

        adios4dolfinx (ADIOS2 BP) for the mesh and the functions; ``meta`` (the hub angle and
        each phase's restart state) as JSON beside it. Written atomically
        (:mod:`tapecoil.core.checkpoint`).
        """
        functions = {**self.checkpoint_functions(), **(extra or {})}
        res = self.strip.resolution
        meta = {**meta, "resolution": {"across": res.across, "along": res.along, "grading": res.grading}}
        tags = {"facets": self.strip.facet_tags, "cells": self.strip.cell_tags}
        checkpoint.write_checkpoint(path, self.strip.mesh, tags, functions, meta, self.comm)

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
        tape.contact.hub_angle = meta["hub_angle"]
        tape.root.set(1.0, meta["hub_angle"])
        tape.contact.turn(meta["hub_angle"])
        return tape, meta
