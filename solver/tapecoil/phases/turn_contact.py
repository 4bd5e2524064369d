"""The real contact of a tape's turns with each other (``contact.turns = "surface"``).

Any part of the mid-surface against any other more than a few search reaches away along the
tape (its own neighbourhood), each pair's side read from the order of the turns of a coil. The
pairs of a state are found once for the energy, the penetration and the force, and assembled on
their own: the turns' contact is not a form (:class:`~tapecoil.contact.self_contact.SelfContact`).
"""

from __future__ import annotations

import numpy as np

from tapecoil.contact.self_contact import SelfContact
from tapecoil.contact.term import PairsAtState, SelfContactTerm
from tapecoil.hub.frame import HubFrame


class TurnContact:
    """Self-contact of the tape's turns, its Verlet search and its pairs at the current state.

    ``nodes``: the shell's :class:`~tapecoil.models.shell.Nodes`; ``h`` [m]; ``penalty`` k
    [N/m^3]; ``smoothing`` delta [m]; ``buffer`` the search's Verlet buffer [m].
    """

    def __init__(
        self, model, nodes, frame: HubFrame, h: float, penalty: float, smoothing: float, buffer: float
    ):
        self.model, self.frame = model, frame
        self.self_contact = SelfContact(
            model, nodes, h, penalty, smoothing, buffer, exclusion=4 * (h + buffer), side_hint=self._coil_side
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
        q = self.model.q.x.array
        return self._measured.get(q, lambda: self.self_contact.pairs(q, self.search))

    def energy(self) -> float:
        """The contact energy of the turns at the current state [J] (collective)."""
        return self.self_contact.energy(self.pairs())

    def max_penetration(self) -> float:
        """Largest penetration of the tape into itself at the current state [m] (collective)."""
        return self.self_contact.max_penetration(self.pairs())

    def add_force(self, force) -> None:
        """Add the contact force dE/dq at the current state to the Function ``force`` (collective)."""
        self.self_contact.add_force(force, self.pairs())

    def accept(self) -> None:
        """After a converged step: read the sides from this state."""
        self.self_contact.accept(self.model.q.x.array)

    def term(self, q, bcs, weight: float = 1.0, previous=None) -> SelfContactTerm:
        """The solver term of the turns' contact (:class:`SelfContactTerm`)."""
        return SelfContactTerm(self.self_contact, q, bcs, weight, previous)
