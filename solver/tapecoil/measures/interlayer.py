"""The pressure between the turns of a stowed coil and the hub's radial reaction, checked by statics.

With the turns' real contact the pressure between them is a result: the contact's forces
across each interface between turn k - 1 and turn k (the hub for k = 0), summed over both
passes of the two-sided contact, are F_k (the force across the interface, the pressure times
its area). A turn is a ring in radial equilibrium under the pressures on its faces and its own
axial force N (a membrane's equilibrium; the bending moment of a turn of constant curvature
adds nothing), so per unit angle b (p_inner r_inner - p_outer r_outer) = N, and over the turn

    F_k - F_{k+1} = integral of N over the turn's angle = 2 pi <N>_k.

Statics predicts the jumps from N alone, read from the turn's strains
(:class:`~tapecoil.measures.section_forces.SectionForces`), without the contact's help; the
hub carries the sum: its push on the tape, through its contact and through the root's clamp,
is the integral of N over the tape that presses on the hub or on a turn beneath, from the root
to the last point where a pair of the contact carries force (beyond it the tape leaves the coil
held by its pull, not by a pressure). Wound-roll mechanics (Altmann 1968, Hakiel 1987) state
the same for a roll of frictionless layers; methods notes.

Each turn is cut opposite the root (:data:`TURN_CUT`): where a turn passes over the step of
the tape's start, its radius changes and its shear force is not zero, and a ring cut there
leaves that shear in its equilibrium. Each pair is counted at the winding angle of its node and
of its closest point on the partner cell: the interface is the lower of the two turns. The
contact's forces are lumped at the nodes, with the Q2 element's unequal weights of corner and
mid-side nodes, so that one cut counts a different share of them in each turn: the forces and
the axial forces are averaged over :data:`CUTS` cuts spread across one element's angle on the
hub.

The inner turns are those wound completely with a complete turn above them: the first turn
is left out (the hub, the root's attachment and the step hold it), and so is the outer one (the
lift-off).
"""

from __future__ import annotations

import math

import numpy as np
from mpi4py import MPI

from tapecoil.measures.measure import Measure

# ``tape`` below: a tape on its hub as the phases hold it (tapecoil.phases.tape_on_hub.TapeOnHub),
# read, never named: the measures sit below the phases

# the statics of a ring holds the jumps to the contact's resolution of the pressure, which the
# penalty spreads over the nodes: 5 % of a jump
JUMP_TOLERANCE = 0.05

# where each turn is cut: half a turn from the root's step [rad of winding angle]
TURN_CUT = math.pi
# how many cuts, spread across one element's angle about TURN_CUT, the measures average over
CUTS = 32

# the ring's identity holds exactly for a coil of circles; the spiral climbs by h a turn and the
# tape bends over the root's step, departures of the order of h / r_hub: 1 % for the benchmark
HUB_TOLERANCE = 0.01


def interface_forces(
    psi_node: np.ndarray, psi_partner: np.ndarray, force: np.ndarray, turns: int, cut: float = TURN_CUT
) -> np.ndarray:
    """The normal force across each interface between turns (``turns`` + 1 of them: k between
    turn k - 1 and turn k, turn k the winding angles [2 pi k + cut, 2 pi (k + 1) + cut)) from
    contact pairs: each pair's node at the winding angle ``psi_node``, its closest point on the
    partner at ``psi_partner``, the force's magnitude ``force`` [N]. A pair belongs to the
    interface above the lower of its two points; pairs that are not a turn apart (a node on its
    own turn's neighbour cell) add nothing."""
    out = np.zeros(turns + 1)
    apart = np.abs(np.abs(psi_node - psi_partner) - 2 * math.pi) < math.pi
    lower = np.minimum(psi_node, psi_partner)[apart]
    interface = np.floor((lower - cut) / (2 * math.pi)).astype(np.int64) + 1
    inside = (interface >= 0) & (interface <= turns)
    np.add.at(out, interface[inside], np.abs(force[apart][inside]))
    return out


def turn_axial_force(
    psi: np.ndarray, axial_force: np.ndarray, turns: int, cut: float = TURN_CUT
) -> np.ndarray:
    """The mean axial force [N] over each turn's winding angles [2 pi k + cut, 2 pi (k + 1) +
    cut), from N at points of winding angle ``psi`` along the tape (sorted along it)."""
    out = np.full(turns, math.nan)
    for k in range(turns):
        start = 2 * math.pi * k + cut
        pick = (psi >= start) & (psi < start + 2 * math.pi)
        if pick.sum() >= 2:
            out[k] = np.trapezoid(axial_force[pick], psi[pick]) / np.ptp(psi[pick])
    return out


def spread_cuts(element_angle: float, count: int = CUTS) -> np.ndarray:
    """``count`` cuts [rad] spread evenly across ``element_angle`` about :data:`TURN_CUT`."""
    return TURN_CUT + element_angle * ((np.arange(count) + 0.5) / count - 0.5)


def complete_turns(angle: float, cut: float = TURN_CUT) -> int:
    """How many turns [2 pi k + cut, 2 pi (k + 1) + cut) a coil wound to ``angle`` holds."""
    return max(math.floor((angle - cut) / (2 * math.pi)), 0)


def interlayer_measures(
    forces: np.ndarray, hub_reaction: float, turn_force: np.ndarray, wound_integral: float
) -> dict:
    """The measures of the interlayer pressure: ``forces`` (K + 1,) the forces across the turns'
    interfaces (k >= 1; ``forces[0]`` is ignored for the hub's ``hub_reaction``, its radial
    push on the tape through its contact and the root's clamp [N]), ``turn_force`` (K,) each
    complete turn's mean axial force [N], ``wound_integral`` the integral of N over the pressed
    tape [N rad]."""
    F = np.array(forces, dtype=float)
    F[0] = hub_reaction
    turns = len(turn_force)
    inner = list(range(1, turns - 1))
    out: dict = {
        "interface_forces": F.tolist(),
        "turn_axial_force": [None if math.isnan(v) else float(v) for v in turn_force],
    }
    ratios = [(F[k] - F[k + 1]) / (2 * math.pi * turn_force[k]) for k in inner]
    if ratios:
        worst = int(np.argmax(np.abs(np.array(ratios) - 1.0)))
        out["pressure_jump"] = Measure(
            "pressure jump across an inner turn x its radius / its axial force (worst turn) [-]",
            ratios[worst],
            1.0,
            JUMP_TOLERANCE,
            "a ring's radial equilibrium, b (p_in r_in - p_out r_out) = N, with N read from the "
            "turn's strains (frictionless turns of a wound roll)",
            "the contact resolves the pressure at the nodes, which the penalty spreads; 5 % of a "
            "jump, whose size is N / r",
            extra={"turn": inner[worst], "ratios": [float(r) for r in ratios]},
        ).to_dict()
    if wound_integral > 0:
        out["hub_reaction"] = Measure(
            "hub's radial push on the tape (contact and root clamp) / integral of N over the "
            "pressed tape [-]",
            hub_reaction / wound_integral,
            1.0,
            HUB_TOLERANCE,
            "the hub carries the sum of the turns' jumps (statics of a coil of rings)",
            "the ring's identity departs from the spiral's by the order of h / r_hub",
            extra={"hub_reaction_N": float(hub_reaction), "pressed_integral_N": float(wound_integral)},
        ).to_dict()
    return out


def coil_interlayer(tape) -> dict | None:
    """The interlayer measures of a full shell's coil at its current state (collective; None
    without the turns' real contact, or with fewer than three complete turns)."""
    if tape.turns is None:
        return None
    comm = tape.comm
    contact = tape.contact
    angle = tape.root.angle
    cuts = spread_cuts(tape.element_length / tape.r_hub)
    turns = complete_turns(angle, cuts.max())
    if turns < 3:
        return None
    surface = tape.turns.surface
    psi_nodes = surface.gather(contact.psi.x.array[: surface.n_owned].copy())
    pairs = tape.turns.pairs()
    cells = tape.turns.self_contact.cells
    psi_partner = np.einsum("pi,pi->p", pairs.N, psi_nodes[cells[pairs.cell]])
    local = np.mean(
        [interface_forces(psi_nodes[pairs.node], psi_partner, pairs.force, turns + 1, c) for c in cuts],
        axis=0,
    )
    forces = comm.allreduce(local, op=MPI.SUM)
    pressing = pairs.force != 0.0
    top = np.maximum(psi_nodes[pairs.node], psi_partner)[pressing]
    pressed_to = comm.allreduce(float(top.max()) if len(top) else -math.inf, op=MPI.MAX)
    sections = tape.section_forces()
    line = tape.centre_line()
    psi_cut = np.interp(sections["xi1"], line["xi1"], line["psi"])
    order = np.argsort(psi_cut)
    psi_cut, N = psi_cut[order], sections["axial_force"][order]
    pressed = psi_cut <= pressed_to
    pressed_integral = float(np.trapezoid(N[pressed], psi_cut[pressed]))
    hub = contact.radial_reaction() + clamp_radial_reaction(tape)
    turn_force = np.mean([turn_axial_force(psi_cut, N, turns, c) for c in cuts], axis=0)
    return interlayer_measures(forces, hub, turn_force, pressed_integral)


def clamp_radial_reaction(tape) -> float:
    """The root clamp's push on the tape away from the hub's axis [N] (collective): the internal
    force dE/dq (strain, the hub's and the turns' contact) on the root edge's displacements,
    which the clamp balances, along the hub's radius at the root."""
    frame = tape.frame
    radial = frame.rotation(tape.root.angle) @ np.array([0.0, 0.0, frame.sign])
    return float(radial @ tape.root_force(tape.internal_force()))
