"""The geometric separation between turns (tapecoil.measures.separation) on synthetic coils.

The coils are Archimedean spirals of a flat strip, r(phi) = r_hub + h/2 + h phi / 2 pi, written
exactly at the nodes of a structured 9-node (Q2) mesh in the snapshot format; successive turns
are then exactly h apart at the same polar angle.

Tolerance. Only the crossed cell is interpolated (the node P lies on the exact spiral). The Q2
interpolant of an arc of angle D through its end and middle points lies inside the circle by at
most r D^4 / 512: with x(t), z(t) interpolating cos, sin of D t / 2 at t = -1, 0, 1,
|p|^2 = 1 - (D/2)^4 t^2 (1 - t^2) / 4 + O(D^6), the largest deficit at t^2 = 1/2. For the test
mesh (17.3 cells a turn, D = 0.363 rad, r <= 13.05 mm) that is 4.4e-3 h; the linear growth of r
with phi is interpolated exactly to the same order, and float32 points (as the writer stores
them) add 2e-5 h. A bump of amplitude A and half-width w (cos^2 profile) adds at most
(D/2)^3 / (9 sqrt 3) A (pi/w)^3 / 2 (quadratic interpolation of its third derivative), 1.7e-3 h for
A = 0.5 h, w = 1.2 rad. TOL = 1e-2 h covers the sum with a margin.
"""

import math

import numpy as np
import pytest

from tapecoil.config import load_config, to_toml
from tapecoil.hub.frame import HubFrame
from tapecoil.measures.separation import (
    material_coordinate,
    quad9_cells,
    separation_bound,
    separation_history,
    separation_measure,
    turn_separation,
)

H = 1.0e-4
R_HUB = 0.0127
WIDTH = 0.03
CELLS_PER_TURN = 17.3  # not a whole number, nor twice one: the crossings fall inside cells
TOL = 1e-2

# lattice places of the VTK Lagrange quadrilateral's nodes (see the module under test)
_I = np.array([0, 2, 2, 0, 1, 2, 1, 0, 1])
_J = np.array([0, 0, 2, 2, 0, 1, 2, 1, 1])


def strip_cells(nx: int, ny: int) -> np.ndarray:
    """Connectivity (nx ny, 9) of a structured Q2 strip; node (I, J) of the lattice is J (2 nx + 1) + I."""
    a, b = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    I = 2 * a.reshape(-1, 1) + _I
    J = 2 * b.reshape(-1, 1) + _J
    return J * (2 * nx + 1) + I


def spiral_length(phi, r0, pitch):
    """Arc length of r = r0 + pitch phi / 2 pi from phi = 0."""
    a = pitch / (2 * math.pi)

    def F(r):
        return (r * np.sqrt(r * r + a * a) + a * a * np.arcsinh(r / a)) / (2 * a)

    return F(r0 + a * phi) - F(r0)


def spiral(nx, ny, turns, bump=None, sense="opposite"):
    """Points (float32), cells, xi1 and axis point of a strip wound ``turns`` times on the hub.

    ``bump(phi)``: a radial displacement [m] added at the wound angle phi.
    """
    frame = HubFrame(R_HUB, H, sense)
    A = frame.axis_point
    r0 = R_HUB + H / 2
    phi = np.linspace(0.0, 2 * math.pi * turns, 2 * nx + 1)
    y = np.linspace(-WIDTH / 2, WIDTH / 2, 2 * ny + 1)
    r = r0 + H * phi / (2 * math.pi) + (0.0 if bump is None else bump(phi))
    # the root leaves the hub's top (bottom) generator towards +x (HubFrame)
    theta = math.pi / 2 - phi if sense == "opposite" else -math.pi / 2 + phi
    P, Y = np.meshgrid(np.arange(len(phi)), y, indexing="xy")
    x, z = A[0] + r * np.cos(theta), A[2] + r * np.sin(theta)
    points = np.stack([x[P], Y, z[P]], axis=-1).reshape(-1, 3)
    xi1 = np.tile(spiral_length(phi, r0, H), len(y))
    return points.astype(np.float32), strip_cells(nx, ny), xi1, A


def flat(nx, ny, length):
    xi1 = np.linspace(0.0, length, 2 * nx + 1)
    y = np.linspace(-WIDTH / 2, WIDTH / 2, 2 * ny + 1)
    X, Y = np.meshgrid(xi1, y, indexing="xy")
    points = np.stack([X, Y, np.zeros_like(X)], axis=-1).reshape(-1, 3)
    return points.astype(np.float32), strip_cells(nx, ny), X.ravel()


def cos2_bump(amplitude, centre, half_width):
    def bump(phi):
        x = (phi - centre) / half_width
        return np.where(np.abs(x) < 1, amplitude * np.cos(0.5 * math.pi * x) ** 2, 0.0)

    return bump


TURNS = 3.0
NX = round(TURNS * CELLS_PER_TURN)
NY = 3
NODE_ANGLE = 2 * math.pi * TURNS / (2 * NX)  # between neighbouring nodes along the tape
# a node of the second turn, where the bump peaks
PEAK_NODE = round((2 * math.pi + 1.0) / NODE_ANGLE)
PEAK = PEAK_NODE * NODE_ANGLE


def measure(points, cells, xi1, A, **kw):
    return turn_separation(points, cells, xi1, A, H, kw.pop("exclusion_length", math.pi * R_HUB), **kw)


def test_uniform_spiral_turns_are_h_apart():
    points, cells, xi1, A = spiral(NX, NY, TURNS)
    m = measure(points, cells, xi1, A)
    assert m.measured == len(points)  # with three turns every radius crosses another one
    assert m.minimum == pytest.approx(1.0, abs=TOL)
    assert np.nanmax(m.per_node) == pytest.approx(1.0, abs=TOL)
    assert m.percentiles[1.0] == pytest.approx(1.0, abs=TOL)
    assert abs(m.offset) == pytest.approx(m.minimum)
    # the other part is a whole turn away along the tape
    turn = 2 * math.pi * np.hypot(*(m.position - A)[[0, 2]])
    assert abs(m.xi1_other - m.xi1) == pytest.approx(turn, rel=0.02)


def test_a_turn_pushed_out_to_half_h():
    points, cells, xi1, A = spiral(NX, NY, TURNS, cos2_bump(0.5 * H, PEAK, 1.2))
    m = measure(points, cells, xi1, A)
    assert m.minimum == pytest.approx(0.5, abs=TOL)
    # at the peak: the bumped node looking out, or the node above it looking in
    peak_xi1 = spiral_length(PEAK, R_HUB + H / 2, H)
    above_xi1 = spiral_length(PEAK + 2 * math.pi, R_HUB + H / 2, H)
    step = spiral_length(PEAK + NODE_ANGLE, R_HUB + H / 2, H) - peak_xi1
    assert sorted([m.xi1, m.xi1_other]) == pytest.approx([peak_xi1, above_xi1], abs=step)
    # elsewhere the turns stay h apart; under the bump the innermost turn sees the second 1.5 h out
    assert m.percentiles[50.0] == pytest.approx(1.0, abs=TOL)
    assert np.nanmax(m.per_node) == pytest.approx(1.5, abs=TOL)


def test_crossing_turns_are_detected():
    # the second turn rises through the third: the separation passes 0 at a node, 2 nodes off the peak
    off = 2 * NODE_ANGLE
    amplitude = H / math.cos(0.5 * math.pi * off / 1.2) ** 2
    points, cells, xi1, A = spiral(NX, NY, TURNS, cos2_bump(amplitude, PEAK, 1.2))
    m = measure(points, cells, xi1, A)
    assert m.minimum < TOL
    centre_line = NY * (2 * NX + 1)
    for node in (PEAK_NODE - 2, PEAK_NODE + 2):
        assert m.per_node[centre_line + node] < TOL
    # between the crossings the third turn lies inside the second, amplitude - h beneath it
    assert m.per_node[centre_line + PEAK_NODE] == pytest.approx(amplitude / H - 1, abs=TOL)


def test_flat_strip_and_exclusion():
    points, cells, xi1 = flat(NX, NY, 0.3)
    m = measure(points, cells, xi1, np.array([0.0, 0.0, -(R_HUB + H / 2)]))
    assert m.measured == 0 and math.isnan(m.minimum) and m.node == -1
    # an exclusion longer than two turns hides every other turn of a three-turn coil
    points, cells, xi1, A = spiral(NX, NY, TURNS)
    assert math.isnan(measure(points, cells, xi1, A, exclusion_length=2.2 * 2 * math.pi * 0.013).minimum)
    # within reach only: a reach below h finds nothing
    assert measure(points, cells, xi1, A, reach=0.5 * H).measured == 0


def test_material_coordinate_from_geometry_gathered_from_two_ranks():
    points, cells, xi1, A = spiral(NX, NY, TURNS)
    # two ranks' pieces, as gathered: the second piece's cells use new copies of its nodes, so the
    # shared lattice column appears twice and the old copies are in no cell; numbering shuffled
    split = 2 * (NX // 2)  # a lattice column on a cell boundary
    n = len(points)
    lattice_i = np.arange(n) % (2 * NX + 1)
    second = np.nonzero(lattice_i >= split)[0]
    copy = np.full(n, -1)
    copy[second] = n + np.arange(len(second))
    right = lattice_i[cells].min(axis=1) >= split
    cells2 = np.where(right[:, None], copy[cells], cells)
    pts2 = np.vstack([points, points[second]])
    order = np.random.default_rng(1).permutation(len(pts2))
    inverse = np.argsort(order)
    pts3, cells3 = pts2[order], inverse[cells2]
    got = material_coordinate(pts3, cells3, A)
    expected = np.concatenate([xi1, xi1[second]])[order]
    # the graph follows the chords between nodes: shorter than the arc by (NODE_ANGLE)^2 / 24
    assert got == pytest.approx(expected, rel=(NODE_ANGLE**2 / 24) * 1.2, abs=1e-6)
    # the same with the strip numbered from the free end: xi1 still starts at the root
    flip = (2 * NX - lattice_i) + (np.arange(n) // (2 * NX + 1)) * (2 * NX + 1)
    reordered = np.empty_like(points)
    reordered[flip] = points
    got = material_coordinate(reordered, flip[cells], A)
    assert got[flip] == pytest.approx(xi1, rel=(NODE_ANGLE**2 / 24) * 1.2, abs=1e-6)


def vtk_cells(cells):
    return np.hstack([np.full((len(cells), 1), 9), cells]).ravel().astype(np.int32)


def test_cells_file_layout():
    cells = strip_cells(3, 2)
    assert np.array_equal(quad9_cells({"cells": vtk_cells(cells), "types": np.full(6, 70)}), cells)
    with pytest.raises(ValueError, match="9-node"):
        quad9_cells({"cells": np.tile([4, 0, 1, 2, 3], 2), "types": np.full(2, 9)})


def write_run(directory, snapshots, cells, sense):
    config = load_config()
    config.hub.radius, config.tape.h, config.coiling.sense = R_HUB, H, sense
    (directory / "config.toml").write_text(to_toml(config))
    folder = directory / "snapshots"
    folder.mkdir()
    np.savez_compressed(folder / "coiling_cells.npz", cells=vtk_cells(cells), types=np.full(len(cells), 70))
    for k, (t, pts) in enumerate(snapshots):
        np.savez_compressed(folder / f"coiling_{k:05d}.npz", t=t, points=pts, kappa_long=pts[:, 0])


@pytest.mark.parametrize("sense", ["opposite", "equal"])
def test_history_of_a_results_directory(tmp_path, sense):
    pts_flat, cells, _ = flat(NX, NY, float(spiral_length(2 * math.pi * TURNS, R_HUB + H / 2, H)))
    uniform = spiral(NX, NY, TURNS, sense=sense)[0]
    bumped = spiral(NX, NY, TURNS, cos2_bump(0.5 * H, PEAK, 1.2), sense=sense)[0]
    write_run(tmp_path, [(0.0, pts_flat), (1.0, uniform), (2.0, bumped), (3.0, uniform)], cells, sense)
    hist = separation_history(tmp_path, "coiling")
    assert hist.t.tolist() == [0.0, 1.0, 2.0, 3.0]
    assert math.isnan(hist.minimum[0]) and hist.measured[0] == 0
    assert hist.minimum[1:] == pytest.approx([1.0, 0.5, 1.0], abs=TOL)
    assert hist.index == 2 and hist.t_min == 2.0 and hist.file_min.name == "coiling_00002.npz"
    assert hist.global_minimum == pytest.approx(0.5, abs=TOL)
    assert hist.percentiles[1.0][1] == pytest.approx(1.0, abs=TOL)
    assert len(separation_history(tmp_path, "coiling", every=2).t) == 3  # 0, 2 and the last
    # on the spiral obstacle the separation is a reading, reported without the bound that the
    # turns' real contact must keep; with the real contact, the half thickness fails it
    reading = separation_measure(tmp_path, "coiling")
    bound, _ = separation_bound(load_config(tmp_path / "config.toml"))
    assert reading["computed"] == pytest.approx(0.5, abs=TOL)
    assert reading["bound"] == "lower" and reading["reference"] == bound
    assert reading["tolerance"] is None and reading["passed"] is None
    config = load_config(tmp_path / "config.toml")
    config.contact.turns = "surface"
    (tmp_path / "config.toml").write_text(to_toml(config))
    held = separation_measure(tmp_path, "coiling")
    assert held["tolerance"] == 0.0 and held["passed"] is False
    assert held["error"] == pytest.approx(bound - 0.5, abs=TOL)


def test_default_mesh_size_coil():
    # the default preset on the benchmark tape: 125 x 9 cells, 4769 nodes, about 6 turns
    turns = 0.5 / (2 * math.pi * 0.0128)
    points, cells, xi1, A = spiral(125, 9, turns)
    m = measure(points, cells, xi1, A)
    # 4 mm cells span 0.31 rad: r D^4 / 512 = 2.4e-3 h
    assert m.minimum == pytest.approx(1.0, abs=5e-3)
    assert np.nanmax(m.per_node) == pytest.approx(1.0, abs=5e-3)
