"""How loose a coil is (tapecoil.measures.deployment.coil_looseness) on synthetic centre lines.

The coils are Archimedean spirals, r(phi) = r_hub + h/2 + h phi / 2 pi, sampled along the tape:
successive turns are exactly h apart at the same polar angle, and the measure's linear
interpolation in the winding angle is exact for a radius linear in it, so the ideal coil opens by
0 to round-off. A lifted stretch of a turn (a cos^2 bump of amplitude A) is read at a sample
point on its crest: the opening is A, where the bump is, to round-off (the last quarter turn
behind the lift-off is left out, where the ploy region lifts the tape). A straight tail leaving
the coil tangentially sweeps less than a quarter turn; loosely wound turns beyond the lift-off
are counted in turns, to the sampling of the angle.
"""

import math

import numpy as np
import pytest

from tapecoil.measures.deployment import coil_looseness

R_HUB, H = 0.0127, 1e-4


def spiral(turns: float, sense: int = 1, per_turn: int = 64, bump=None):
    """Centre-line points (s, radius, polar angle) of a spiral of ``turns``; the polar angle
    wrapped into (-3 pi / 2, pi / 2] as the hub's frame reads it, running in ``sense``;
    ``bump = (phi_0, half_width, amplitude)`` lifts the tape around winding angle phi_0."""
    phi = np.linspace(0.0, 2 * math.pi * turns, int(per_turn * turns) + 1)
    radius = R_HUB + H / 2 + H * phi / (2 * math.pi)
    if bump is not None:
        centre, width, amplitude = bump
        near = np.abs(phi - centre) < width
        radius = radius + np.where(near, amplitude * np.cos(0.5 * math.pi * (phi - centre) / width) ** 2, 0.0)
    s = np.concatenate([[0.0], np.cumsum(radius[1:] * np.diff(phi))])
    return s, radius, wrapped(0.3 - sense * phi)


def wrapped(angle):
    """Polar angles as the hub's frame gives them, in (-3 pi / 2, pi / 2]."""
    return (angle + 1.5 * math.pi) % (2 * math.pi) - 1.5 * math.pi


def coil_opening(s, radius, angle, coiled, h):
    found = coil_looseness(s, radius, angle, coiled, h)
    return found["coil_opening"], found["coil_opening_at"]


def with_tail(s, radius, angle, length=0.3):
    """The coil with a straight tape leaving its last point tangentially, ``length`` [m] long."""
    step = angle[-1] - angle[-2]  # the sense the tape winds in
    p = radius[-1] * np.array([np.cos(angle[-1]), np.sin(angle[-1])])
    tangent = np.sign(step) * np.array([-np.sin(angle[-1]), np.cos(angle[-1])])
    d = np.linspace(1e-3, length, 60)
    tail = p + np.outer(d, tangent)
    return (
        np.concatenate([s, s[-1] + d]),
        np.concatenate([radius, np.hypot(tail[:, 0], tail[:, 1])]),
        np.concatenate([angle, wrapped(np.arctan2(tail[:, 1], tail[:, 0]))]),
    )


@pytest.mark.parametrize("sense", [1, -1])
def test_an_ideal_coil_does_not_open(sense):
    s, radius, angle = spiral(5.5, sense)
    opening, _ = coil_opening(s, radius, angle, s[-1], H)
    assert abs(opening) < 1e-9 * H


@pytest.mark.parametrize("sense", [1, -1])
def test_a_lifted_stretch_opens_the_coil_by_its_lift_where_it_is(sense):
    crest = 2 * math.pi * 2.5  # half-way round the third turn, on a sample point (64 a turn)
    s, radius, angle = spiral(5.5, sense, bump=(crest, 0.8, 0.6 * H))
    opening, at = coil_opening(s, radius, angle, s[-1], H)
    assert opening == pytest.approx(0.6 * H, rel=1e-9)
    assert at == pytest.approx(s[160], rel=1e-12)  # the crest's sample: 2.5 turns of 64


def test_only_the_coil_behind_the_lift_off_counts():
    """A lift beyond the lift-off is the tape leaving the coil, not the coil opening; a straight
    tail past it is left out too."""
    crest = 2 * math.pi * 4.5
    s, radius, angle = spiral(5.0, bump=(crest, 0.8, 3 * H))
    lift = s[np.searchsorted(s, s[-1] * 0.8)]
    assert coil_opening(s, radius, angle, lift, H)[0] == pytest.approx(0.0, abs=1e-9 * H)
    assert coil_opening(s, radius, angle, s[-1], H)[0] == pytest.approx(3 * H, rel=1e-9)
    s2, r2, a2 = with_tail(*spiral(5.0))
    assert coil_opening(s2, r2, a2, s[-1], H)[0] == pytest.approx(0.0, abs=1e-9 * H)


def test_the_last_quarter_turn_behind_the_lift_off_does_not_count():
    """There the ploy region lifts the tape off the coil gradually; a lift 3/8 of a turn behind
    the lift-off counts."""
    lift_turns = 4.0
    s, radius, angle = spiral(5.0, bump=(2 * math.pi * (lift_turns - 0.2), 0.3, H))
    lift = s[int(64 * lift_turns)]
    assert coil_opening(s, radius, angle, lift, H)[0] == pytest.approx(0.0, abs=1e-9 * H)
    s, radius, angle = spiral(5.0, bump=(2 * math.pi * (lift_turns - 0.375), 0.3, H))
    assert coil_opening(s, radius, angle, lift, H)[0] == pytest.approx(H, rel=1e-9)


@pytest.mark.parametrize("sense", [1, -1])
def test_a_straight_tape_leaving_the_coil_leaves_no_loose_turn(sense):
    s, radius, angle = spiral(5.0, sense)
    s, radius, angle = with_tail(s, radius, angle, length=0.5)
    found = coil_looseness(s, radius, angle, s[len(s) - 61], H)
    assert found["loose_turns"] == 0.0


@pytest.mark.parametrize("sense", [1, -1])
def test_turns_wound_loosely_beyond_the_lift_off_are_counted(sense):
    """The last 1.5 turns of a 5-turn coil lifted 4 h off the turns beneath (a coil whose outer
    turns have come loose together), then a straight tail: the lift-off lies where the tight
    coil ends, and beyond it 1.5 turns are wound loosely."""
    phi_loose = 2 * math.pi * 3.5
    s, radius, angle = spiral(5.0, sense)
    phi = np.linspace(0.0, 2 * math.pi * 5.0, len(s))
    radius = radius + np.where(phi > phi_loose, 4 * H * np.minimum((phi - phi_loose) / 0.5, 1.0), 0.0)
    lift = s[np.searchsorted(phi, phi_loose)]
    s, radius, angle = with_tail(s, radius, angle, length=0.5)
    found = coil_looseness(s, radius, angle, lift, H)
    sampling = 2 * math.pi / 64 / (2 * math.pi)  # an angle step of the samples, in turns
    assert found["loose_turns"] == pytest.approx(1.5, abs=sampling)
    assert found["coil_opening"] == pytest.approx(0.0, abs=1e-9 * H)  # tight behind the lift-off


def test_less_than_a_turn_wound_has_no_opening():
    s, radius, angle = spiral(0.9)
    assert coil_opening(s, radius, angle, s[-1], H) == (0.0, 0.0)
    assert coil_opening(s[:1], radius[:1], angle[:1], s[-1], H) == (0.0, 0.0)
