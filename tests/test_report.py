"""Results a user can read: figures, renders, the animation and report.html of a short run."""

import json

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import config_from_dict


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A short tape coiled by 4 rad (more than half a turn of coiled interior) and released 3 ms,
    its hub free to turn (25 times the tape's rotary inertia)."""
    from tapecoil.app.pipeline import run

    config = config_from_dict(
        {
            "tape": {"L": 0.12},
            "coiling": {"hub_angle": 4.0},
            "mesh": {"preset": "coarse"},
            "hub": {"inertia": 1e-5},
            "deployment": {"t_end": 0.003, "release_time": 0.0005, "hub": "free"},
            "output": {"vtx_every": 2},
        }
    )
    directory = tmp_path_factory.mktemp("report") / "run"
    summary = run(config, directory, comm=MPI.COMM_SELF, progress=False, report=True)
    assert summary["coiling"]["completed"]
    return directory


def _colourful(path) -> float:
    """Fraction of pixels that are clearly coloured (lines, surfaces), not white, grey or black."""
    from PIL import Image

    rgb = np.asarray(Image.open(path).convert("RGB"), dtype=float)
    return float(((rgb.max(axis=2) - rgb.min(axis=2)) > 60).mean())


EXPECTED = (
    "coiling_energies",
    "coiling_forces",
    "coil_radius",
    "coil_profiles",
    "deployment_lambda",
    "deployment_energies",
    "deployment_root_loads",
    "deployment_hub",
    "coiling_sequence",
    "stowed",
    "deployment_sequence",
)


def test_every_picture_is_drawn(run_dir):
    for name in EXPECTED:
        path = run_dir / "figures" / f"{name}.png"
        assert path.is_file(), name
        # data drawn in colour, not empty axes or a blank window
        assert _colourful(path) > 0.002, name


def test_animation_has_a_frame_per_snapshot(run_dir):
    from PIL import Image

    gif = Image.open(run_dir / "figures" / "animation.gif")
    snapshots = list((run_dir / "snapshots").glob("*_[0-9]*.npz"))
    # (a GIF encoder may merge two identical consecutive frames, e.g. the first flattening steps)
    assert len(snapshots) > 5 and len(snapshots) - 2 <= gif.n_frames <= len(snapshots)


def test_report_ties_numbers_and_pictures_together(run_dir):
    html = (run_dir / "report.html").read_text()
    for name in EXPECTED:
        assert f'src="figures/{name}.png"' in html, name
    assert 'src="figures/animation.gif"' in html
    summary = json.loads((run_dir / "summary.json").read_text())
    for row in summary["validation"]:
        assert row["label"].split(" [")[0] in html
    assert "pass" in html


def test_report_command_remakes_the_report(run_dir, capsys):
    from tapecoil.app.cli import main

    (run_dir / "report.html").unlink()
    assert main(["report", str(run_dir)]) == 0
    assert (run_dir / "report.html").is_file()
    assert str(run_dir / "report.html") in capsys.readouterr().out
