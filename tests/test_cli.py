"""The command line: theory table and JSON, and refusal of a broken configuration."""

import json
import shutil
import subprocess

import pytest

from tapecoil.cli import main


def test_theory_json_numbers(capsys):
    assert main(["theory", "--json"]) == 0
    p = json.loads(capsys.readouterr().out)["predictions"]
    assert p["T_deploy_hub"]["value"] == pytest.approx(0.443, rel=5e-3)
    assert p["T_deploy_ode"]["value"] == pytest.approx(0.436, rel=5e-3)
    assert p["t90_ode"]["value"] == pytest.approx(0.352, rel=5e-3)
    assert p["coiling_tension"]["value"] == pytest.approx(0.384, rel=5e-3)
    assert p["coil_radius"]["value"] == pytest.approx(13.27e-3, rel=5e-3)
    assert p["stored_energy"]["unit"] == "J"


def test_theory_table(capsys):
    assert main(["theory"]) == 0
    out = capsys.readouterr().out
    assert "0.4426 s" in out and "Eq. 2.23" in out
    assert "0.3842 N" in out and "13.27 mm" in out


def test_broken_config_refused(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("[tape]\nnu = 0.7\n")
    assert main(["theory", str(path)]) == 2
    err = capsys.readouterr().err
    assert "tape.nu = 0.7 is out of range: must be in (-1, 0.5)" in err
    assert err.count("\n") == 1


def test_config_command_round_trips(tmp_path, capsys):
    assert main(["config"]) == 0
    path = tmp_path / "c.toml"
    path.write_text(capsys.readouterr().out)
    assert main(["theory", str(path), "--json"]) == 0


@pytest.mark.skipif(shutil.which("tapecoil") is None, reason="console script not installed")
def test_console_script():
    out = subprocess.run(["tapecoil", "theory", "--json"], capture_output=True, text=True, check=True).stdout
    assert json.loads(out)["predictions"]["coiling_tension"]["value"] == pytest.approx(0.3842, rel=1e-3)


def test_coil_refuses_bad_input_before_computing(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("[coiling]\ntension = -1.0\n")
    assert main(["coil", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "coiling.tension" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # nothing was started


def test_coil_short_run_writes_results(tmp_path, capsys):
    import json

    path = tmp_path / "short.toml"
    path.write_text("[tape]\nL = 0.1\n[coiling]\nhub_angle = 0.3\n[mesh]\npreset = 'coarse'\n")
    out = tmp_path / "out"
    assert main(["coil", str(path), "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["completed"] and summary["hub_angle"] == 0.3
    for name in ("config.toml", "history.csv", "summary.json", "coil.bp", "stowed/meta.json"):
        assert (out / name).exists(), name


def test_deploy_refuses_a_missing_checkpoint(tmp_path, capsys):
    assert main(["deploy", str(tmp_path / "nowhere"), "--out", str(tmp_path / "out")]) == 2
    assert "is not a stowed checkpoint" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_run_pipeline_then_deploy_from_its_checkpoint(tmp_path, capsys):
    """tapecoil run (coil, stow, deploy) on a short tape, then tapecoil deploy from its checkpoint."""
    path = tmp_path / "short.toml"
    path.write_text(
        "[tape]\nL = 0.1\n[coiling]\nhub_angle = 0.5\n[mesh]\npreset = 'coarse'\n"
        "[deployment]\nt_end = 0.001\nrelease_time = 0.0005\n"
    )
    out = tmp_path / "run"
    # stops at t_end before lambda = 1: exit status 1, but every result is written
    assert main(["run", str(path), "--out", str(out), "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["coiling"]["completed"]
    deployment = result["deployment"]
    assert deployment["time"] == pytest.approx(0.001) and "t_end" in deployment["message"]
    for name in (
        "summary.json",
        "stowed/meta.json",
        "deployment_history.csv",
        "deployment_summary.json",
        "deployment.bp",
        "deployed/meta.json",
    ):
        assert (out / name).exists(), name
    # the deployment again, from the checkpoint (configuration read beside it)
    assert main(["deploy", str(out / "stowed"), "--out", str(tmp_path / "again"), "--json"]) == 1
    again = json.loads(capsys.readouterr().out)
    assert again["lambda"] == pytest.approx(deployment["lambda"], abs=1e-6)
    assert again["measures"]["energy"]["stowed"] == pytest.approx(
        deployment["measures"]["energy"]["stowed"], rel=1e-6
    )
