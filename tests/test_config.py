"""Configuration: defaults, TOML round trip, and one clear error per kind of bad input."""

import dataclasses
import inspect
import math
import re

import pytest

from tapecoil.config import Config, ConfigError, ConfigWarning, config_from_dict, load_config, to_toml


def test_defaults_are_the_benchmark_tape():
    c = load_config()
    assert (c.tape.R, c.tape.alpha, c.tape.h, c.tape.L) == (0.0151, 2.3562, 1e-4, 0.5)
    assert (c.tape.E, c.tape.nu, c.tape.rho_l) == (130e9, 0.3, 0.0293)
    assert c.hub.radius == 0.0127
    assert (c.coiling.hub_angle, c.coiling.tension) == (36.0, 1.0)


def test_toml_round_trip(tmp_path):
    c = Config()
    c.tape.L = 0.25
    c.coiling.hub_angle = 12.0  # the default 36 rad needs more than 0.25 m of tape
    c.mesh.preset = "coarse"
    c.contact.stop_penetration = 0.25
    c.contact.search_margin = 1.5
    c.solver.petsc_options = {"pc_factor_mat_solver_type": "mumps", "snes_monitor": True}
    c.coiling.petsc_options = {"snes_max_it": 40}
    c.deployment.petsc_options = {"snes_linesearch_type": "bt", "snes_rtol": 1e-9}
    path = tmp_path / "c.toml"
    path.write_text(to_toml(c))
    assert load_config(path) == c


def test_integer_accepted_for_float(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text("[coiling]\nhub_angle = 12\n")
    c = load_config(path)
    assert c.coiling.hub_angle == 12.0 and isinstance(c.coiling.hub_angle, float)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"tape": {"h": 0.0}}, r"tape\.h = 0\.0 is out of range: must be > 0 \[m\]"),
        ({"tape": {"h": -1e-4}}, r"tape\.h .* must be > 0"),
        ({"tape": {"alpha": 0.0}}, r"tape\.alpha .* must be in \(0, 6\.28319\)"),
        ({"tape": {"alpha": 2 * math.pi}}, r"tape\.alpha .* must be in \(0, 6\.28319\)"),
        ({"tape": {"nu": 0.5}}, r"tape\.nu .* must be in \(-1, 0\.5\)"),
        ({"tape": {"nu": -1.0}}, r"tape\.nu .* must be in \(-1, 0\.5\)"),
        ({"hub": {"radius": 0.0}}, r"hub\.radius = 0\.0 is out of range: must be > 0"),
        ({"hub": {"radius": -0.01}}, r"hub\.radius .* must be > 0"),
        ({"tape": {"h": 1e-3}}, r"tape\.h = 0\.001 m is not much smaller than tape\.R .* h/R <= 0\.05"),
        ({"tape": {"L": 0.01}}, r"tape\.L .* at least the arc width"),
        ({"tape": {"E": "130e9"}}, r"tape\.E must be a number \(got str"),
        ({"tape": {"E": True}}, r"tape\.E must be a number \(got bool"),
        ({"tape": {"E": math.inf}}, r"tape\.E must be a finite number"),
        ({"tape": {"thickness": 1e-4}}, r"unknown key tape\.thickness \(known in \[tape\]: E, L, R"),
        ({"tapes": {}}, r"unknown section \[tapes\]"),
        ({"mesh": {"preset": "medium"}}, r"mesh\.preset = 'medium' is not allowed: must be one of 'coarse'"),
        ({"mesh": {"elements_across": 2.5}}, r"mesh\.elements_across must be an integer"),
        ({"deployment": {"rho_inf": 1.5}}, r"deployment\.rho_inf .* must be in \[0, 1\]"),
        ({"deployment": {"dt": 1.0, "t_end": 0.5}}, r"deployment\.dt .* smaller than deployment\.t_end"),
        # the step sizes are the phases' own, in their units (coiling.max_step, deployment.dt)
        ({"solver": {"initial_step": 0.05}}, r"unknown key solver\.initial_step"),
        ({"solver": {"max_step": 0.25}}, r"unknown key solver\.max_step"),
        ({"solver": {"min_step": 1.0}}, r"solver\.min_step = 1\.0 is out of range: must be in \[0, 1\)"),
        ({"solver": {"max_cutbacks": -1}}, r"solver\.max_cutbacks .* must be in \[0, 100\]"),
        ({"solver": {"petsc_options": {"ksp_type": [1]}}}, r"solver\.petsc_options\.ksp_type must be"),
        (
            {"coiling": {"petsc_options": {"snes_monitor": {}}}},
            r"coiling\.petsc_options\.snes_monitor must be",
        ),
        ({"deployment": {"petsc_options": "snes_monitor"}}, r"deployment\.petsc_options must be a table"),
        ({"hub": {"radius": 1e-4}}, r"hub\.radius .* must exceed twice tape\.h"),
        ({"coiling": {"tension": -1.0}}, r"coiling\.tension .* must be >= 0 \[N\]"),
        (
            {"coiling": {"hub_angle": 200.0}},
            r"coiling\.hub_angle = 200 rad is more than the tape can coil: the whole tape "
            r"\(tape\.L = 0\.5 m\) is on the hub .* after 38\.3 rad \(6\.1 turns\)",
        ),
        # the default 36 rad on a tape too short for it
        ({"tape": {"L": 0.1}}, r"coiling\.hub_angle = 36 rad .*tape\.L = 0\.1 m.* after 7\.805 rad"),
        ({"contact": {"stop_penetration": 0.0}}, r"contact\.stop_penetration = 0\.0 .* \(0, 100\]"),
        ({"contact": {"stop_penetration": 150.0}}, r"stop_penetration = 150\.0 .* \(0, 100\]"),
        ({"contact": {"search_margin": 0.0}}, r"contact\.search_margin = 0\.0 is out of range: must be > 0"),
        ({"contact": {"search_margin": -1.0}}, r"contact\.search_margin .* must be > 0"),
        ({"hub": {"inertia": -1e-6}}, r"hub\.inertia .* must be >= 0 \[kg m\^2\]"),
        (
            {"deployment": {"hub": "driven"}},
            r"deployment\.hub = 'driven' is not allowed: must be one of 'fixed'",
        ),
        # an inertia on a hub that does not turn would act on nothing
        ({"hub": {"inertia": 1e-5}}, r"hub\.inertia = 1e-05 kg m\^2 acts only on a hub free to turn"),
        (
            {"model": {"kind": "beam"}},
            r"model\.kind = 'beam' is not allowed: must be one of 'shell', 'hybrid'",
        ),
        # the hybrid's window on the shell model would act on nothing
        ({"model": {"window_ahead": 0.1}}, r"model\.window_ahead acts only on the hybrid model"),
        (
            {"model": {"kind": "hybrid", "window_move": 0.0}},
            r"model\.window_move = 0\.0 .* must be > 0 \[m\]",
        ),
        (
            {"model": {"kind": "hybrid", "window_release": -0.1}},
            r"model\.window_release = -0\.1 .* must be > 0 \[m\]",
        ),
        ({"model": {"window_release": 0.2}}, r"model\.window_release acts only on the hybrid model"),
        (
            {"model": {"kind": "hybrid"}, "coiling": {"sense": "equal"}},
            r"model\.kind = 'hybrid' needs coiling\.sense = 'opposite'",
        ),
        (
            {"model": {"kind": "hybrid"}, "mesh": {"grading": 2.0}},
            r"model\.kind = 'hybrid' needs mesh\.grading = 1",
        ),
        (
            {"model": {"kind": "hybrid"}, "deployment": {"rho_inf": 1.0}},
            r"model\.kind = 'hybrid' needs deployment\.rho_inf < 1",
        ),
        (
            {"model": {"kind": "hybrid", "window_ahead": 0.5}},
            r"model\.window_ahead \+ model\.window_behind = 0\.525 m must be shorter than the tape",
        ),
    ],
)
def test_bad_values_are_refused_with_key_and_range(data, message):
    with pytest.raises(ConfigError, match=message):
        config_from_dict(data)


def test_hub_angle_up_to_the_whole_tape_is_accepted():
    from tapecoil.theory import max_hub_angle

    largest = max_hub_angle(0.5, 0.0127, 1e-4)
    assert config_from_dict({"coiling": {"hub_angle": largest}}).coiling.hub_angle == largest
    with pytest.raises(ConfigError, match=r"coiling\.hub_angle .* after 38\.3 rad"):
        config_from_dict({"coiling": {"hub_angle": largest * (1 + 1e-9)}})


def test_contact_stop_and_search_keys_load_from_toml(tmp_path):
    assert (Config().contact.stop_penetration, Config().contact.search_margin) == (1.0, 2.0)
    path = tmp_path / "c.toml"
    path.write_text("[contact]\nstop_penetration = 0.75\nsearch_margin = 0.5\n")
    c = load_config(path).contact
    assert (c.stop_penetration, c.search_margin) == (0.75, 0.5)
    assert isinstance(c.stop_penetration, float)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (
            {"coiling": {"tension": 0.0}},
            r"coiling\.tension = 0 N is below the 0\.374 N the hub needs \(Eq\. 2\.6 .*\): "
            r"with too little pull the tape does not wrap onto the hub",
        ),
        ({"coiling": {"tension": 0.3}}, r"coiling\.tension = 0\.3 N is below the 0\.374 N"),
        (
            {"hub": {"radius": 4 * 0.0151}, "coiling": {"hub_angle": 5.0}},
            r"coiling\.tension = 1 N is below the 7\.15 N the hub needs \(Eq\. 2\.9",
        ),
    ],
)
def test_a_pull_below_the_tension_the_hub_needs_is_named_but_loads_quietly(data, message, recwarn):
    config = config_from_dict(data)
    # no warning on loading: a report, a plot or a tension study loads it too
    assert not [w for w in recwarn if issubclass(w.category, ConfigWarning)]
    (found,) = config.coiling_warnings()
    assert re.match(message, found)


@pytest.mark.parametrize(
    "data",
    [
        {"coiling": {"tension": 0.374}},
        # loss of uniqueness: no law gives the tension, so nothing to warn against
        {"hub": {"radius": 2 * 0.0151}, "coiling": {"hub_angle": 5.0, "tension": 0.0}},
        {"hub": {"radius": 4 * 0.0151}, "coiling": {"hub_angle": 5.0, "tension": 7.2}},
    ],
)
def test_enough_pull_is_not_warned_of(data):
    assert config_from_dict(data).coiling_warnings() == []


def test_the_default_pull_is_not_warned_of(recwarn):
    assert load_config().coiling.tension == 1.0
    assert load_config().coiling_warnings() == []
    assert not [w for w in recwarn if issubclass(w.category, ConfigWarning)]


@pytest.mark.parametrize("section", [f for f in dataclasses.fields(Config)], ids=lambda f: f.name)
def test_every_key_is_documented_with_its_unit(section):
    # cleandoc: Python 3.13 strips the docstring's indentation itself, earlier versions do not
    doc = inspect.cleandoc(section.default_factory.__doc__).split("Attributes:")[1]
    entries = dict(re.findall(r"^ {4}(\w+): (.*?)(?=^ {4}\w+:|\Z)", doc, re.M | re.S))
    for f in dataclasses.fields(section.default_factory):
        key = f"{section.name}.{f.name}"
        assert f.name in entries, f"{key} is not in the Attributes of its section's docstring"
        if f.type in ("float", "int"):
            assert re.search(r"\[[^\]]+\]", entries[f.name]), f"{key}: no unit in brackets"


def test_file_errors(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_config(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[tape\nh = 1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(bad)
