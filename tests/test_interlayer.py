"""The interlayer pressure's measures: the forces across the turns' interfaces, each turn's axial
force and the ring's statics, on a coil whose pairs and axial force are known."""

import math

import numpy as np
import pytest

from tapecoil.measures.interlayer import (
    TURN_CUT,
    complete_turns,
    interface_forces,
    interlayer_measures,
    spread_cuts,
    turn_axial_force,
)


def _ring_coil(turns: int, N, end: float, pairs_per_turn: int = 400):
    """Pairs of a coil of frictionless rings wound to the winding angle ``end``, in equilibrium:
    per unit winding angle, the force across the interface above the point at psi is the sum
    of the axial forces of the turns above it, N(psi + 2 pi) + N(psi + 4 pi) + ..., so that each
    ring's jump is its own axial force. Half of the pairs are the inner turn's nodes on the
    outer turn's cells, half the other way; the closest point sits a little off the node."""

    def above(psi):
        return sum(
            np.where(psi + 2 * math.pi * j < end, N(psi + 2 * math.pi * j), 0.0) for j in range(1, turns + 2)
        )

    lower = (np.arange(pairs_per_turn * turns) + 0.5) * (2 * math.pi / pairs_per_turn)
    force = above(lower) * (2 * math.pi / pairs_per_turn)
    inner_node = np.arange(len(lower)) % 2 == 0
    psi_node = np.where(inner_node, lower, lower + 2 * math.pi)
    psi_partner = np.where(inner_node, lower + 2 * math.pi + 1e-3, lower - 1e-3)
    return psi_node, psi_partner, force


def test_a_coil_of_rings_in_equilibrium_gives_each_turn_its_jump():
    def N(psi):
        return 1.6 + 0.01 * psi  # the axial force grows along the coil, as in a wound tape

    end = 2 * math.pi * 6.3
    psi_node, psi_partner, force = _ring_coil(6, N, end)
    K = complete_turns(end)
    assert K == 5  # the turns are cut half a turn from the root
    forces = interface_forces(psi_node, psi_partner, force, K + 1)
    psi = np.linspace(0.0, end, 20001)
    turn_force = turn_axial_force(psi, N(psi), K)
    for k in range(K):
        # the mean over the turn of a linear N is its value at the turn's middle
        assert turn_force[k] == pytest.approx(N(2 * math.pi * (k + 0.5) + TURN_CUT), rel=1e-5)
    for k in range(1, K):
        # the ring's statics: the jump across turn k is the integral of its axial force
        assert forces[k] - forces[k + 1] == pytest.approx(2 * math.pi * turn_force[k], rel=1e-3)
    jump = interlayer_measures(forces, 0.0, turn_force, 1.0)["pressure_jump"]
    assert jump["passed"]
    assert max(abs(r - 1.0) for r in jump["ratios"]) < 1e-3


def test_a_pair_counts_at_its_lower_point_whichever_side_its_node_is_on():
    psi_lower = TURN_CUT + 2 * math.pi - 0.01  # just below the cut between turns 0 and 1
    psi_node = np.array([psi_lower, psi_lower + 2 * math.pi])
    psi_partner = np.array([psi_lower + 2 * math.pi + 0.005, psi_lower - 0.005])
    forces = interface_forces(psi_node, psi_partner, np.array([1.0, 2.0]), 3)
    # the node's side decides nothing: both pairs lie over turn 0
    assert forces.tolist() == [0.0, 3.0, 0.0, 0.0]


def test_pairs_between_points_not_a_turn_apart_add_nothing():
    psi_node = np.array([10.0, 10.0, 10.0])
    psi_partner = np.array([10.05, 10.0 + 4 * math.pi, 10.0 + 2 * math.pi])
    forces = interface_forces(psi_node, psi_partner, np.array([5.0, 7.0, 1.0]), 4)
    assert forces.sum() == pytest.approx(1.0)


def test_a_ring_out_of_equilibrium_fails_the_jump():
    turn_force = np.array([1.0, 1.0, 1.0, 1.0])
    forces = np.array([0.0, 3 * 2 * math.pi, 2 * 2 * math.pi, 1.1 * 2 * math.pi, 0.0])
    jump = interlayer_measures(forces, 0.0, turn_force, 0.0)["pressure_jump"]
    assert not jump["passed"]
    assert jump["turn"] == 2 and jump["computed"] == pytest.approx(0.9)


def test_the_hub_carries_the_sum_of_the_jumps_to_a_percent():
    turn_force = np.array([1.0, 1.0, 1.0, 1.0])
    forces = np.array([0.0, 3.0, 2.0, 1.0, 0.0]) * 2 * math.pi
    pressed = 4 * 2 * math.pi  # the integral of N = 1 over four pressed turns
    held = interlayer_measures(forces, 1.005 * pressed, turn_force, pressed)["hub_reaction"]
    assert held["passed"] and held["computed"] == pytest.approx(1.005)
    short = interlayer_measures(forces, 0.98 * pressed, turn_force, pressed)["hub_reaction"]
    assert not short["passed"]


def test_cuts_spread_across_an_element_undo_the_lumping_of_the_nodal_forces():
    """A coil of rings of N = 1 whose pressure is lumped at the nodes of Q2 elements one radian
    long (a coarse mesh's), as the contact lumps it: corner nodes a third of an element's
    share, mid-side nodes two thirds. One cut counts a different share of them in each turn;
    cuts spread across one element's angle read each jump to a percent."""
    element, turns = 0.98, 7
    end = 2 * math.pi * turns
    nodes = np.arange(0.0, end - 2 * math.pi, element / 2)
    share = np.where(np.arange(len(nodes)) % 2 == 0, element / 3, 2 * element / 3)
    # the force per unit angle under the point at psi: N = 1 times the turns above it, smoothed
    # along the coil (a spiral's), so that each ring's jump is 1 x 2 pi
    above = (end - nodes) / (2 * math.pi) - 1
    force = share * above
    psi_partner = nodes + 2 * math.pi
    K = complete_turns(end - 2 * math.pi)
    one = interface_forces(nodes, psi_partner, force, K + 1)
    cuts = spread_cuts(element)
    spread = np.mean([interface_forces(nodes, psi_partner, force, K + 1, c) for c in cuts], axis=0)
    lumped = [(one[k] - one[k + 1]) / (2 * math.pi) for k in range(1, K - 1)]
    averaged = [(spread[k] - spread[k + 1]) / (2 * math.pi) for k in range(1, K - 1)]
    assert max(abs(r - 1) for r in lumped) > 0.1
    assert max(abs(r - 1) for r in averaged) < 0.01
