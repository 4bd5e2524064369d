"""The real contact of a tape's turns with each other (``contact.turns = "surface"``).

Any part of the mid-surface against any other more than a few search reaches away along the
tape (its own neighbourhood), each pair's side read from the order of the turns of a coil. The
pairs of a state are found once for the energy, the penetration and the force, and assembled on
their own: the turns' contact is not a form (:class:`~tapecoil.contact.self_contact.SelfContact`).
"""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from tapecoil.contact.self_contact import SelfContact
from tapecoil.contact.surface import ContactSurface
from tapecoil.contact.term import Numbering, PairsAtState, SelfContactTerm, block_numbering
from tapecoil.hub.frame import HubFrame


class TurnContact:
    """Self-contact of the tape's turns, its Verlet search and its pairs at the current state.

    ``surface``: the tape's :class:`~tapecoil.contact.surface.ContactSurface` (the full shell's
    mid-surface, or a hybrid's window joined to its beam's strip); ``h`` [m]; ``penalty`` k
    [N/m^3]; ``smoothing`` delta [m]; ``buffer`` the search's Verlet buffer [m].
    """

    def __init__(
        self,
        surface: ContactSurface,
        frame: HubFrame,
        h: float,
        penalty: float,
        smoothing: float,
        buffer: float,
    ):
        self.surface, self.frame = surface, frame
        self.self_contact = SelfContact(
            surface, h, penalty, smoothing, buffer, exclusion=4 * (h + buffer), side_hint=self._coil_side
        )
        self.search = self.self_contact.new_search()
        self._measured = PairsAtState(self.self_contact)

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

    def pairs(self):
        """The turns' contact pairs at the current state, once per state for all the measures."""
        key = np.concatenate(self.surface.state())
        return self._measured.get(key, lambda: self.self_contact.pairs(self.search))

    def energy(self) -> float:
        """The contact energy of the turns at the current state [J] (collective)."""
        return self.self_contact.energy(self.pairs())

    def max_penetration(self) -> float:
        """Largest penetration of the tape into itself at the current state [m] (collective)."""
        return self.self_contact.max_penetration(self.pairs())

    def nodal_forces(self) -> np.ndarray:
        """The contact force dE/dx (N, 3) on every node of the surface at the current state, on
        every rank (collective)."""
        local = self.self_contact.nodal_forces(self.pairs())
        return self.self_contact.comm.allreduce(local)

    def add_force(self, force) -> None:
        """Add the contact force dE/dq at the current state to the shell's Function ``force`` (a
        surface of one shell: its nodes' displacement dofs; collective)."""
        vec = force.x.petsc_vec
        local = self.self_contact.nodal_forces(self.pairs())
        rows = self.surface.u_dofs.ravel().astype(PETSc.IntType)
        vec.setValues(rows, local.ravel(), addv=PETSc.InsertMode.ADD)
        vec.assemblyBegin()
        vec.assemblyEnd()
        vec.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def accept(self) -> None:
        """After a converged step: read the sides from this state."""
        self.self_contact.accept()

    def term(self, numbering: Numbering, weight: float = 1.0, previous=None) -> SelfContactTerm:
        """The solver term of the turns' contact (:class:`SelfContactTerm`) for a solver whose
        unknowns sit as ``numbering`` says; ``previous``: (weight, the blocks' old Functions)."""
        return SelfContactTerm(self.self_contact, numbering, weight, previous)

    def shell_term(self, q, bcs, weight: float = 1.0, previous=None) -> SelfContactTerm:
        """The term for a solver of the shell's state ``q`` alone with Dirichlet conditions
        ``bcs``; ``previous``: (weight, q_old)."""
        old = None if previous is None else (previous[0], [previous[1]])
        return self.term(block_numbering(q.function_space, bcs), weight, old)
