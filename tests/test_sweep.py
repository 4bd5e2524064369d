"""Parameter sweeps: the sweep file is checked before anything runs; cases on sub-communicators."""

import json
from pathlib import Path

import pytest
from mpi4py import MPI

from tapecoil.config import ConfigError

# the study coils its own 1 rad; the configuration's hub_angle must still suit a 0.1 m tape on
# every hub of the sweep (at most 7.3 rad, on the 0.9 R hub), the default 36 rad does not
TINY = """
[tape]
L = 0.1
[coiling]
hub_angle = 1.0
[mesh]
preset = "coarse"
[sweep]
study = "coiling_tension"
[sweep.parameters]
"hub.radius_over_R" = [0.6, 0.9]
[sweep.tension]
preset = "coarse"
length = 0.1
hub_angle = 1.0
window = [0.5, 1.0]
max_step = 0.1
section_window = []
"""


def test_the_demo_sweep_file_is_valid():
    from pathlib import Path

    from tapecoil.app.sweep import load_sweep

    sweep = load_sweep(Path(__file__).parents[1] / "demos" / "coiling_tension_sweep.toml")
    cases = sweep.cases()
    assert [c["hub.radius_over_R"] for c in cases] == [0.5, 0.6, 0.7, 0.8, 0.9]
    assert sweep.config(cases[0]).hub.radius == pytest.approx(0.5 * 0.0151)


def test_the_steel_tension_sweep_file_is_valid():
    from tapecoil.app.sweep import load_sweep

    sweep = load_sweep(Path(__file__).parents[1] / "demos" / "coiling_tension_steel.toml")
    assert sweep.study == "coiling_tension" and sweep.config(sweep.cases()[0]).tape.R == 0.0192


@pytest.mark.parametrize("name", ["coiling_regimes.toml", "coiling_regimes_benchmark.toml"])
def test_the_regime_sweep_files_are_valid(name):
    from tapecoil.app.sweep import load_sweep
    from tapecoil.phases.wrapping import WrapStudy

    sweep = load_sweep(Path(__file__).parents[1] / "demos" / name)
    ratios = [c["hub.radius_over_R"] for c in sweep.cases()]
    assert ratios[0] == 0.4 and ratios[-1] == 5.25 and sweep.study == "wrapping"
    assert isinstance(sweep.study_options(), WrapStudy)


def test_cases_are_every_combination(tmp_path):
    from tapecoil.app.sweep import load_sweep

    path = tmp_path / "s.toml"
    path.write_text(
        '[sweep]\nstudy = "coil"\n[sweep.parameters]\n'
        '"tape.h" = [1e-4, 2e-4]\n"coiling.tension" = [1, 2, 3]\n'
    )
    sweep = load_sweep(path)
    cases = sweep.cases()
    assert len(cases) == 6 and cases[-1] == {"tape.h": 2e-4, "coiling.tension": 3}
    assert sweep.config(cases[-1]).tape.h == 2e-4


WRAPPING = '[sweep]\nstudy = "wrapping"\n[sweep.parameters]\n"tape.h" = [1e-4]\n[sweep.wrapping]\n'


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[tape]\nL = 1\n", r"has no \[sweep\] table"),
        ('[sweep]\nstudy = "dance"\n[sweep.parameters]\n"tape.h" = [1e-4]\n', r"sweep\.study = 'dance'"),
        ('[sweep]\n[sweep.parameters]\n"tape.height" = [1e-4]\n', r'"tape\.height" is neither'),
        ('[sweep]\n[sweep.parameters]\n"tape.h" = 1e-4\n', r"must be a non-empty list"),
        ('[sweep]\nranks_per_case = 0\n[sweep.parameters]\n"tape.h" = [1e-4]\n', r"ranks_per_case"),
        (
            '[sweep]\n[sweep.parameters]\n"tape.nu" = [0.3, 0.7]\n',
            r"sweep case .*tape\.nu = 0\.7 is out of range",
        ),
        (
            '[sweep]\nstudy = "coil"\n[sweep.parameters]\n"tape.h" = [1e-4]\n[sweep.tension]\nlength = 1\n',
            r"only",
        ),
        (
            '[sweep]\n[sweep.parameters]\n"tape.h" = [1e-4]\n[sweep.tension]\nlen = 1\n',
            r"sweep\.tension\.len",
        ),
        (
            WRAPPING + "pull = 1\n",
            r"sweep\.wrapping\.pull",
        ),
        (
            '[sweep]\n[sweep.parameters]\n"tape.h" = [1e-4]\n[sweep.wrapping]\nrelease = 0.01\n',
            r"sweep\.wrapping is for study = 'wrapping' only",
        ),
        (
            WRAPPING + "conform_angle = 350.0\n",
            r"conform_angle and wrap_angle",
        ),
        (
            '[sweep]\n[sweep.parameters]\n"tape.h" = [1e-4]\n[sweep.tension]\nsection_window = [1.0, 6.0]\n',
            r"sweep\.tension: section_window = \[1\.0, 6\.0\]",
        ),
        (  # the hybrid cannot deploy a coil its window never left: refused before the 36 rad case
            '[model]\nkind = "hybrid"\n[sweep]\nstudy = "run"\n[sweep.parameters]\n'
            '"coiling.hub_angle" = [36.0, 2.0]\n',
            r"sweep case \{'coiling.hub_angle': 2.0\}: coiling.hub_angle = 2 rad winds at most",
        ),
    ],
)
def test_a_bad_sweep_is_refused_before_anything_runs(tmp_path, text, message):
    from tapecoil.app.sweep import load_sweep

    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_sweep(path)


class _Started(Exception):
    """Raised by the stand-in for the pipeline: the sweep got as far as computing a case."""


def test_a_coil_sweep_warns_of_each_weak_pull_before_computing(tmp_path, monkeypatch):
    """Loading the sweep is quiet; running it warns of every case's weak pull before the first
    case computes, and the case's run.log has its own."""
    import warnings

    from tapecoil.app import pipeline
    from tapecoil.app.sweep import case_name, load_sweep, run_sweep
    from tapecoil.config import ConfigWarning

    path = tmp_path / "weak.toml"
    path.write_text('[sweep]\nstudy = "coil"\n[sweep.parameters]\n"coiling.tension" = [0.1, 0.2, 1.0]\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConfigWarning)
        sweep = load_sweep(path)
    out, seen = tmp_path / "out", {}

    def started(config, directory, **kwargs):
        seen["warnings"] = [str(w.message) for w in record if issubclass(w.category, ConfigWarning)]
        seen["log"] = (Path(directory) / "run.log").read_text()
        raise _Started

    monkeypatch.setattr(pipeline, "run", started)
    with pytest.warns(ConfigWarning) as record, pytest.raises(_Started):
        run_sweep(sweep, out, MPI.COMM_SELF, progress=False)
    first, second = seen["warnings"]  # the 1 N case has enough pull
    assert first.startswith(
        "sweep case {'coiling.tension': 0.1}: coiling.tension = 0.1 N is below the 0.374 N"
    )
    assert second.startswith("sweep case {'coiling.tension': 0.2}: coiling.tension = 0.2 N is below")
    assert seen["log"].count("WARNING configuration: " + first) == 1
    assert not (out / case_name(1, sweep.cases()[1])).exists()


@pytest.mark.mpi
def test_sweep_cases_on_sub_communicators_match_serial_runs(tmp_path):
    """Two cases on two groups of one rank each: each agrees with the case run alone."""
    from tapecoil.app.sweep import case_name, load_sweep, run_sweep
    from tapecoil.phases.tension_study import TensionStudy, coiling_tension

    comm = MPI.COMM_WORLD
    directory = comm.bcast(str(tmp_path), root=0)
    path = f"{directory}/tiny.toml"
    if comm.rank == 0:
        open(path, "w").write(TINY)
    comm.barrier()
    sweep = load_sweep(path)
    summary = run_sweep(sweep, f"{directory}/out", comm, progress=False)
    assert summary["groups"] == comm.size and len(summary["cases"]) == 2
    for i, case in enumerate(sweep.cases()):
        alone = coiling_tension(
            sweep.config(case),
            MPI.COMM_SELF,
            TensionStudy(
                preset="coarse", length=0.1, hub_angle=1.0, window=(0.5, 1.0), max_step=0.1, section_window=()
            ),
        )
        stored = json.loads(open(f"{directory}/out/{case_name(i, case)}/summary.json").read())
        assert stored["coiling_tension"]["computed"] == pytest.approx(alone["computed"], rel=1e-8)
        assert summary["cases"][i]["coiling_tension"] == pytest.approx(alone["computed"], rel=1e-8)
    if comm.rank == 0:
        assert (tmp_path / "out" / "sweep.png").is_file()
        assert (tmp_path / "out" / "sweep_summary.csv").read_text().count("\n") == 3
