"""Coiling: hub attachment, contact obstacle, winding angles, a short coiling run, checkpoints."""

import dataclasses
import math

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import CoilingConfig, Config, TapeConfig


def short_tape(hub_angle=1.0, L=0.12) -> Config:
    """The benchmark section on a short tape, coarse mesh: a run of seconds."""
    cfg = Config()
    return dataclasses.replace(
        cfg,
        tape=dataclasses.replace(TapeConfig(), L=L),
        coiling=dataclasses.replace(CoilingConfig(), hub_angle=hub_angle),
        mesh=dataclasses.replace(cfg.mesh, preset="coarse"),
    )


@pytest.fixture(scope="module")
def coiled_short():
    """A short tape flattened and coiled by 1 rad on one rank (shared by the tests below)."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    model = CoilingProblem(short_tape(), MPI.COMM_SELF)
    run = CoilingRun(model)
    run.flatten()
    run.coil(1.0)
    return model, run.result.history


def test_hub_root_section_flattens_and_turns_onto_the_hub(cfg):
    from tapecoil.hub.attachment import HubRoot
    from tapecoil.phases.coiling import CoilingProblem

    model = CoilingProblem(short_tape(), MPI.COMM_SELF)
    root: HubRoot = model.root
    s = np.linspace(-cfg.tape.b / 2, cfg.tape.b / 2, 41)
    xi = np.vstack([np.zeros_like(s), s])
    curved, d0 = root.section_at(xi, 0.0)
    assert np.allclose(curved, model.strip.geometry.phi0(xi), atol=1e-15)
    assert np.allclose(d0, model.strip.geometry.frame(xi)[2], atol=1e-14)
    flat, d1 = root.section_at(xi, 1.0)
    assert np.allclose(flat[1], s) and np.allclose(flat[2], 0.0)
    assert np.allclose(d1, [[0.0], [0.0], [1.0]])
    # the flattened section keeps its length for any f (inextensible)
    for f in (0.3, 0.7):
        p, _ = root.section_at(xi, f)
        assert np.sum(np.linalg.norm(np.diff(p, axis=1), axis=0)) == pytest.approx(cfg.tape.b, rel=1e-3)
    # turned by the hub angle, the flat root's centre line stays on the hub's mid-surface radius
    # and has moved towards -x (the coiling sense)
    root.set(1.0, 0.8)
    u = root.values[0]
    x = u.function_space.tabulate_dof_coordinates()
    centre = np.argmin(np.abs(x[:, 1]) + np.abs(x[:, 0]))
    pos = model.strip.geometry.phi0(x[centre, :2, None])[:, 0] + u.x.array.reshape(-1, 3)[centre]
    rel = pos - model.frame.axis_point
    assert math.hypot(rel[0], rel[2]) == pytest.approx(cfg.hub.radius + cfg.tape.h / 2, rel=1e-12)
    assert math.atan2(rel[2], rel[0]) == pytest.approx(math.pi / 2 + 0.8, rel=1e-12)


def test_obstacle_staircase_climbs_one_thickness_per_turn():
    from tapecoil.phases.coiling import CoilingProblem

    model = CoilingProblem(short_tape(hub_angle=20.0), MPI.COMM_SELF)
    c = model.contact
    w, h, r = c.ramp_width, c.h, c.r_hub
    psi = np.array(
        [0.0, 2 * math.pi - w - 1e-9, 2 * math.pi - w / 2, 2 * math.pi, 3 * math.pi, 4 * math.pi + 0.1]
    )
    expected = np.array([r, r, r + h / 2, r + h, r + h, r + 2 * h])
    assert np.allclose(c.spiral_radius(psi), expected, rtol=0, atol=1e-15)


def test_winding_angle_is_unwrapped_from_step_to_step():
    from tapecoil.phases.coiling import CoilingProblem

    model = CoilingProblem(short_tape(), MPI.COMM_SELF)
    c = model.contact
    psi0 = c.psi.x.array.copy()
    # on the straight tape: 0 at the root (on top of the hub), rising along it towards pi/2
    assert abs(psi0.min()) < 1e-12 and 1.0 < psi0.max() < math.pi / 2
    # turning every point rigidly about the axis by 5 rad in 0.5 rad steps (as the coil does)
    # leaves psi unchanged in the hub frame
    nodes = c.nodes
    from tapecoil.core.rotation import rotation_matrix

    q = model.model.q.x.array
    x0 = nodes.reference
    a = model.frame.axis_point[:, None]
    for angle in np.arange(0.5, 5.01, 0.5):
        x = rotation_matrix(np.array([0.0, -1.0, 0.0]), angle) @ (x0 - a) + a
        q[nodes.u_dofs] = (x - x0).T
        c.update(angle)
    assert np.allclose(c.psi.x.array, psi0, atol=1e-9)


def test_short_coil_wraps_onto_the_hub(coiled_short, cfg):
    _, history = coiled_short
    coil = [r for r in history if r["phase"] == "coil"]
    assert coil[-1]["hub_angle"] == pytest.approx(1.0)
    h, r_hub = cfg.tape.h, cfg.hub.radius
    # the wound length is the mid-surface arc r_hub + h/2 times the angle, to a few percent
    # (the ploy region lifts off just before the tangent point)
    assert coil[-1]["coiled_length"] == pytest.approx((r_hub + h / 2) * 1.0, rel=0.05)
    # the free end has slid towards the hub by about the same length
    assert -coil[-1]["end_slide"] == pytest.approx(coil[-1]["coiled_length"], rel=0.05)
    # contact holds: penetration a small fraction of the thickness
    assert max(r["max_penetration"] for r in coil) < 0.2 * h
    # the tension carried at the free end is the pull (force control)
    assert coil[-1]["tension"] == pytest.approx(cfg.coiling.tension, rel=1e-6)
    # the stored energy grows with the hub angle at about w b r per radian
    energy = np.array([r["strain_energy"] for r in coil])
    assert np.all(np.diff(energy) > 0)
    assert all(math.isfinite(v) for r in history for v in r.values() if isinstance(v, float))
    # hub torque from the energy balance against steady coiling: each radian winds r of tape,
    # storing b w(r) per metre, against the pull T (the last steps, past the start-up)
    from tapecoil import theory

    tp = cfg.tape
    rho = r_hub + h / 2
    steady = rho * (cfg.coiling.tension + tp.b * theory.energy_density(rho, tp.R, cfg.wall.bending))
    late = [r["hub_torque"] for r in coil if r["hub_angle"] > 0.6 and r["hub_torque"] != ""]
    assert late and np.median(late) == pytest.approx(steady, rel=0.10)


def test_turning_the_hub_back_pays_the_tape_out_reversibly(cfg):
    """Coiled by 2 rad, then turned back to 1 rad with the pull held (a driven deployer paying
    out, quasi-static): the free end slides back out by the wound length, the deployed fraction
    lambda grows, and the hub torque from the energy balance of the steps is the coiling's at the
    same angles (frictionless and quasi-static, the path is reversible; steady coiling
    rho (T + b w(rho)) within 10 % as for the coiling)."""
    from tapecoil import theory
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    model = CoilingProblem(short_tape(hub_angle=2.0), MPI.COMM_SELF)
    run = CoilingRun(model)
    run.flatten()
    run.coil(2.0)
    wound = len(run.result.history)
    run.coil(1.0, start_angle=2.0)
    out, back = run.result.history[:wound], run.result.history[wound:]
    assert back[-1]["hub_angle"] == pytest.approx(1.0) and all(r["phase"] == "coil" for r in back)
    assert np.all(np.diff([r["hub_angle"] for r in back]) < 0)
    tp, h, r_hub = cfg.tape, cfg.tape.h, cfg.hub.radius
    rho = r_hub + h / 2
    assert back[-1]["end_slide"] - out[-1]["end_slide"] == pytest.approx(rho * 1.0, rel=0.05)
    assert back[-1]["lambda"] > out[-1]["lambda"] + 0.5 * rho / tp.L
    assert back[-1]["coiled_length"] == pytest.approx(rho * 1.0, rel=0.05)  # as when coiling
    steady = rho * (cfg.coiling.tension + tp.b * theory.energy_density(rho, tp.R, cfg.wall.bending))
    torque = [r["hub_torque"] for r in back[1:] if r["hub_torque"] != ""]
    assert torque and np.median(torque) == pytest.approx(steady, rel=0.10)


def test_checkpoint_round_trip(coiled_short, tmp_path):
    from tapecoil.phases.coiling import read_checkpoint, write_checkpoint

    model, _ = coiled_short
    res = model.strip.resolution
    meta = {
        "hub_angle": model.root.angle,
        "tension": float(model.tension.value),
        "completed": True,
        "resolution": {"across": res.across, "along": res.along, "grading": res.grading},
    }
    write_checkpoint(model, tmp_path / "stowed", meta)
    restored, meta2 = read_checkpoint(tmp_path / "stowed", model.config, MPI.COMM_SELF)
    assert meta2["hub_angle"] == pytest.approx(1.0)
    e0, e1 = model.tape.energies(), restored.tape.energies()
    for key in ("membrane", "bending", "shear", "contact"):
        assert e1[key] == pytest.approx(e0[key], rel=1e-10, abs=1e-14)
    assert np.allclose(np.sort(restored.contact.psi.x.array), np.sort(model.contact.psi.x.array))


def test_the_free_end_needs_room_for_its_elements_and_to_come_off_the_coil():
    """The room the free end needs (phases.coiling.free_end_room) against the free length
    L - x(theta) of Eq. 4.3's spiral: 36 rad (the default, 30.7 mm free) passes on every preset;
    the bound is 2.4 free-end elements on the coarse mesh and, on the default one, 2.7 times
    the length x_c of the guide line inside the coil (x_c = 3.9 mm at 37.5 rad)."""
    from tapecoil.config import ConfigError, MeshConfig
    from tapecoil.phases.coiling import check_free_end_room, free_end_room
    from tapecoil.theory import coiled_length_from_rotation

    def config(angle, preset):
        return dataclasses.replace(
            Config(), coiling=CoilingConfig(hub_angle=angle), mesh=MeshConfig(preset=preset)
        )

    for preset in ("coarse", "default", "fine"):
        check_free_end_room(config(36.0, preset))
    free, for_coil, for_mesh = free_end_room(config(37.5, "default"))
    assert free == pytest.approx(0.5 - coiled_length_from_rotation(37.5, 0.0127, 1e-4), rel=1e-12)
    t_c = 1e-4 * 37.5 / (2 * math.pi)
    assert for_coil == pytest.approx(2.7 * math.sqrt(2 * 0.0127 * t_c + t_c**2), rel=1e-12)
    assert for_mesh == pytest.approx(2.4 * 0.004, rel=1e-12)
    # the largest angle each mesh accepts: where the free length meets the bound
    assert free_end_room(config(36.05, "coarse"))[0] > 0.030 > free_end_room(config(36.06, "coarse"))[0]
    check_free_end_room(config(37.5, "default"))
    with pytest.raises(ConfigError, match=r"coiling\.hub_angle = 37\.52 rad leaves 10\.4 mm"):
        check_free_end_room(config(37.52, "default"))


@pytest.mark.slow
def test_the_largest_hub_angle_the_coarse_mesh_accepts_coils_to_completion(tmp_path):
    """Slow (`make validate`): the coarse benchmark at the largest hub angle its free end's room
    accepts (36.05 rad, 30.0 mm free), coiled as `tapecoil coil` coils it, reaches that angle,
    the tape kept within contact.stop_penetration of its turns."""
    from tapecoil.phases.coiling_run import run_coiling

    coarse = dataclasses.replace(Config().mesh, preset="coarse")
    config = dataclasses.replace(Config(), coiling=CoilingConfig(hub_angle=36.05), mesh=coarse)
    summary, _ = run_coiling(config, tmp_path, MPI.COMM_WORLD, progress=False)
    assert summary["completed"], summary.get("message")
    assert summary["hub_angle"] == pytest.approx(36.05, abs=1e-9)


def test_a_tape_that_sinks_too_deep_stops_the_run_with_the_last_accepted_state():
    """A penalty far too soft (1e7 N/m^3 against the derived 8e9) lets the short tape sink into
    the hub as it wraps: steps that go deeper than contact.stop_penetration = 1 h are cut back,
    and the run stops, naming the key, where no shorter step stays within it; the state kept
    is the last accepted one, within the limit and close to it."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    cfg = short_tape(hub_angle=2.5)
    cfg = dataclasses.replace(cfg, contact=dataclasses.replace(cfg.contact, penalty=1e7))
    model = CoilingProblem(cfg, MPI.COMM_SELF)
    result = CoilingRun(model).run()
    h = cfg.tape.h
    assert not result.completed
    assert "contact.stop_penetration = 1 h" in result.message and "last converged load" in result.message
    assert result.history[-1]["hub_angle"] < 2.0
    assert all(r["max_penetration"] <= h for r in result.history)
    assert 0.9 * h < model.tape.max_penetration() <= h


def test_bad_coiling_config_is_rejected_before_computing():
    from tapecoil.config import ConfigError, config_from_dict

    with pytest.raises(ConfigError, match=r"coiling\.hub_angle"):
        config_from_dict({"coiling": {"hub_angle": -1.0}})


@pytest.mark.mpi
@pytest.mark.parametrize("predictor", ["secant", "shift"])
def test_two_ranks_coil_as_one(predictor, coil_last_row):
    """The same short coiling run distributed over the ranks and on each rank alone."""
    cfg = short_tape(hub_angle=0.5)
    cfg = dataclasses.replace(cfg, coiling=dataclasses.replace(cfg.coiling, predictor=predictor))
    parallel, serial = coil_last_row(cfg, MPI.COMM_WORLD, 0.5), coil_last_row(cfg, MPI.COMM_SELF, 0.5)
    assert MPI.COMM_WORLD.size > 1
    for key in ("strain_energy", "bending_energy", "coiled_length", "outer_radius", "end_slide"):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-6), key
    assert parallel["hub_angle"] == serial["hub_angle"]


def test_resume_from_checkpoint_matches_an_uninterrupted_run(tmp_path):
    """Coil to 0.5 rad, stop, resume from the checkpoint to 1 rad: as if never stopped."""
    import csv

    from tapecoil.phases.coiling_run import run_coiling

    half, _ = run_coiling(short_tape(hub_angle=0.5), tmp_path / "half", MPI.COMM_SELF, progress=False)
    assert half["completed"]
    resumed, _ = run_coiling(
        short_tape(hub_angle=1.0),
        tmp_path / "resumed",
        MPI.COMM_SELF,
        resume=tmp_path / "half" / "stowed",
        progress=False,
    )
    direct, _ = run_coiling(short_tape(hub_angle=1.0), tmp_path / "direct", MPI.COMM_SELF, progress=False)
    assert resumed["completed"] and direct["completed"]
    assert resumed["hub_angle"] == pytest.approx(1.0)
    rows = {
        name: list(csv.DictReader((tmp_path / name / "coiling_history.csv").open()))
        for name in ("half", "resumed", "direct")
    }
    # the resumed history goes on from the checkpoint's: the first part is the stopped run's
    assert rows["resumed"][: len(rows["half"])] == rows["half"]
    assert float(rows["resumed"][len(rows["half"])]["hub_angle"]) > 0.5
    for key in ("strain_energy", "coiled_length", "end_slide"):
        assert float(rows["resumed"][-1][key]) == pytest.approx(float(rows["direct"][-1][key]), rel=1e-5), key
    assert resumed["run"]["steps"] == len([r for r in rows["resumed"] if r["phase"] == "coil"])


def test_along_tape_shift_reproduces_nodes_and_smooth_fields():
    """A whole element's shift returns the nodal values; a smooth field moves to spline accuracy."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.predictors import AlongTape

    model = CoilingProblem(short_tape(), MPI.COMM_SELF)
    nodes = model.contact.nodes
    along = AlongTape(nodes, MPI.COMM_SELF)
    assert len(along.lines) == 2 * model.strip.resolution.across + 1
    q = np.zeros_like(model.model.q.x.array)
    L, l = model.config.tape.L, model.element_length
    x, s = nodes.xi
    field = np.column_stack([np.sin(2 * math.pi * x / L) * (1 + s), x**2, s * x, np.cos(x / L), x])
    q[nodes.u_dofs], q[nodes.theta_dofs] = field[:, :3], field[:, 3:]
    inside = (x >= l) & (x <= L - l)
    whole = along.values_at(q, -l)
    source = np.isclose(x[:, None] - l, x[None, :], atol=1e-12) & np.isclose(
        s[:, None], s[None, :], atol=1e-12
    )
    assert np.allclose(whole[inside], field[source.argmax(axis=1)][inside], atol=1e-13)
    part = along.values_at(q, 0.3 * l)
    moved = x + 0.3 * l
    expected = np.column_stack(
        [np.sin(2 * math.pi * moved / L) * (1 + s), moved**2, s * moved, np.cos(moved / L), moved]
    )
    # a cubic spline through nodes dx = l/2 apart errs by at most (5/384) dx^4 max|f''''| away
    # from the ends; components of degree <= 2 in xi_1 come out exact
    interior = (x >= l) & (x <= L - 2 * l)
    bound = 5 / 384 * (l / 2) ** 4 * (2 * math.pi / L) ** 4 * (1 + np.abs(s).max())
    assert np.abs(part[interior, 0] - expected[interior, 0]).max() < bound
    assert np.allclose(part[interior][:, [1, 2, 4]], expected[interior][:, [1, 2, 4]], rtol=0, atol=1e-14)


def test_predictor_choice_follows_the_element_length():
    from tapecoil.phases.predictors import choose_predictor

    r_hub = 0.0127
    assert choose_predictor("auto", 0.004, r_hub) == "shift"  # default mesh
    assert choose_predictor("auto", 0.0125, r_hub) == "secant"  # coarse mesh
    assert choose_predictor("secant", 0.004, r_hub) == "secant"


def test_shift_and_secant_predictors_reach_the_same_state():
    """The predictor changes the path of Newton, not the equilibrium (a short tape, 1.5 rad)."""
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    states = {}
    for predictor in ("shift", "secant"):
        cfg = short_tape(hub_angle=1.5)
        cfg = dataclasses.replace(cfg, coiling=dataclasses.replace(cfg.coiling, predictor=predictor))
        model = CoilingProblem(cfg, MPI.COMM_SELF)
        assert model.predictor == predictor
        run = CoilingRun(model)
        run.flatten()
        run.coil(1.5)
        states[predictor] = run.result.history[-1]
    for key in ("strain_energy", "coiled_length", "end_slide", "outer_radius"):
        assert states["shift"][key] == pytest.approx(states["secant"][key], rel=1e-6), key


def _wound_interior(model, lo, hi):
    """Cell values over the wound material lo < psi < hi [rad], inner 60 % of the width."""
    from tapecoil.measures.coiling import coiled_cells

    cells = coiled_cells(model.tape)
    b = model.config.tape.b
    mask = (cells["psi"] > lo) & (cells["psi"] < hi) & (np.abs(cells["xi2"]) <= 0.3 * b)
    return {k: v[mask] for k, v in cells.items()}


def test_equal_sense_coil_curves_with_its_section_and_flattens_on_the_hub(coiled_short):
    """Equal sense, one turn: the coil bends the way the section curves, the opposite sense the other.

    Both read at the converged state, from the shell's own curvature fields and, for the turn's
    radius, from the nodes' positions about the hub axis.
    """
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    cfg = short_tape(hub_angle=2 * math.pi)
    # the section's edges start inside the hub (the equal-sense section curves towards it)
    contact = dataclasses.replace(cfg.contact, stop_penetration=100.0)
    cfg = dataclasses.replace(cfg, coiling=dataclasses.replace(cfg.coiling, sense="equal"), contact=contact)
    model = CoilingProblem(cfg, MPI.COMM_SELF)
    result = CoilingRun(model).run()
    assert result.completed, result.message
    tp, r_hub = cfg.tape, cfg.hub.radius
    assert model.frame.axis_point[2] > 0  # the hub on the concave side, above the tape

    equal = _wound_interior(model, 1.0, 2 * math.pi - 1.0)
    opposite = _wound_interior(coiled_short[0], 0.2, 0.8)
    assert len(equal["psi"]) > 0 and len(opposite["psi"]) > 0
    rho = r_hub + tp.h / 2
    # the section's transverse curvature is +1/R: equal sense curves the same way
    assert np.all(equal["kappa_long"] > 0) and np.all(opposite["kappa_long"] < 0)
    assert np.mean(equal["kappa_long"]) * rho == pytest.approx(1.0, abs=0.1)
    # the section is flattened on the hub (|kappa_trans| R = 1 on the free tape)
    assert np.max(np.abs(equal["kappa_trans"])) * tp.R < 0.15
    # the first turn's mid-surface lies h/2 off the hub, read from the node positions
    nodes = model.contact.nodes
    x = nodes.positions(model.model.q.x.array)
    distance = np.hypot(x[0], x[2] - (r_hub + tp.h / 2))  # the hub axis lies at z = r_hub + h/2
    psi = model.contact.psi.x.array
    wound = (psi > 1.0) & (psi < 2 * math.pi - 1.0) & (np.abs(nodes.xi[1]) < 1e-9)
    assert wound.any()
    assert np.all(np.abs(distance[wound] - rho) < 0.5 * tp.h)
    # the equal-sense plate estimate (physics brief Sec. 10): the stored energy of the coiled
    # length and the surface stresses, with the nu terms' sign changed, within the opposite
    # sense's tolerances (5 % and 10 %)
    from tapecoil.measures.coiling import coil_measures

    measures = coil_measures(model.tape)
    assert measures["stored_energy_coiled"]["passed"], measures["stored_energy_coiled"]
    for name in ("stress_x", "stress_y"):
        assert measures[name]["passed"], measures[name]


def test_surface_contact_keeps_the_second_turn_off_the_first():
    """contact.turns = "surface": a short tape coiled past its first turn (the climb over the root).

    Read from the nodes' positions, independently of the contact's gap: along the centre line
    the second turn's mid-surface lies at least 0.9 h outside the first at the same winding
    angle (the coarse mesh: 12 mm elements on a 12.7 mm hub), and the contact forces of the
    turns on each other sum to zero.
    """
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.coiling_run import CoilingRun

    angle = 2 * math.pi + 1.2
    cfg = short_tape(hub_angle=angle)
    cfg = dataclasses.replace(cfg, contact=dataclasses.replace(cfg.contact, turns="surface"))
    model = CoilingProblem(cfg, MPI.COMM_SELF)
    result = CoilingRun(model).run()
    assert result.completed, result.message
    line = model.tape.centre_line()
    h = cfg.tape.h
    psi = np.linspace(2 * math.pi + 0.3, angle - 0.3, 7)
    outer = np.interp(psi, line["psi"], line["radius"])
    inner = np.interp(psi - 2 * math.pi, line["psi"], line["radius"])
    assert np.all(outer - inner >= 0.9 * h), (outer - inner) / h
    import dolfinx

    force = dolfinx.fem.Function(model.model.W)
    model.tape.add_self_contact_force(force)
    f = force.x.array[model.contact.nodes.u_dofs]
    assert np.abs(f).sum() > 0
    assert np.abs(f.sum(axis=0)).max() <= 1e-10 * np.abs(f).sum()
    # the contact's own time is counted, a part of the assembly's and the linear solve's
    timing = model.solver.timing_per_iteration()
    assert 0 < timing["terms"] < timing["assembly"] + timing["linear_solve"]


def test_hub_torque_from_the_reactions_matches_the_energy_balance(coiled_short):
    """Two readings of the hub torque: the root's reactions and the steps' energy balance."""
    from tapecoil.measures.coiling import hub_torque_measure

    _, history = coiled_short
    measure = hub_torque_measure(history)
    assert measure is not None and measure["work_energy_balance_J"] > 0
    assert measure["passed"], measure


def test_a_body_turned_with_the_hub_adds_its_energy_and_follows_the_hub_angle():
    """CoilingProblem's ``obstacles``: a body with a penalty energy (here a spring pulling every
    point of the tape towards a height the body sets from the hub angle) is turned with the hub
    and its energy is the model's."""
    import dolfinx

    from tapecoil.core.dofs import global_scalar
    from tapecoil.phases.coiling import CoilingProblem
    from tapecoil.phases.tape_on_hub import TapeOnHub

    class Spring:
        def __init__(self, tape):
            self.height = dolfinx.fem.Constant(tape.model.mesh, 0.0)
            self.energy = 0.5 * (tape.model.u[2] - self.height) ** 2 * tape.model.dx
            self.angles = []

        def turn(self, angle):
            self.angles.append(angle)
            self.height.value = angle

    tape = TapeOnHub(short_tape(), MPI.COMM_SELF)
    spring = Spring(tape)
    model = CoilingProblem(short_tape(), MPI.COMM_SELF, tape=tape, obstacles=(spring,))
    model.set_flattening(0.5)
    model.set_hub_angle(0.25)
    assert spring.angles == [0.0, 0.25]
    total = global_scalar(dolfinx.fem.form(model.energy), MPI.COMM_SELF)
    alone = global_scalar(dolfinx.fem.form(tape.energy), MPI.COMM_SELF)
    # the undeformed tape: the spring's energy is (1/2) 0.25^2 times the reference area
    cfg = short_tape()
    assert total - alone == pytest.approx(0.5 * 0.25**2 * cfg.tape.L * cfg.tape.b, rel=1e-3)
