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


def _tape_pixels(rgb: np.ndarray) -> np.ndarray:
    """Where a render shows the colour map's saturated colours (viridis, shaded): the tape, not
    the tan hub (a pale colour), the white ground or the black text and frames."""
    top, bottom = rgb.max(axis=2), rgb.min(axis=2)
    return (top > 25) & (top - bottom > 0.5 * top)


FIGURES = (
    "coiling_energies",
    "coiling_forces",
    "coil_radius",
    "coil_profiles",
    "deployment_lambda",
    "deployment_energies",
    "deployment_root_loads",
    "deployment_coil",
    "deployment_hub",
)
RENDERS = ("coiling_sequence", "stowed", "deployment_sequence")
EXPECTED = FIGURES + RENDERS


def test_every_picture_is_drawn(run_dir):
    """Every figure has its data drawn, and every panel of every render shows the tape.

    A figure's lines colour several times more of it than its legend's samples alone do (a
    legend of three entries on each of two axes, with no data, colours a fraction of the bound
    below; the sparsest figure, coil_radius, several times it). A render's colour bar alone
    fills a strip along the foot of the first panel and is viridis as the tape is; so each
    panel is judged above that strip, where only the tape is coloured so: a correct panel shows
    it over several times the bound below (the coil at 4 rad, mostly behind the hub, the
    least), a panel without the tape shows none.
    """
    from PIL import Image

    from tapecoil.post.render import PANEL

    for name in FIGURES:
        path = run_dir / "figures" / f"{name}.png"
        assert path.is_file(), name
        assert _colourful(path) > 0.0013, name
    for name in RENDERS:
        path = run_dir / "figures" / f"{name}.png"
        assert path.is_file(), name
        rgb = np.asarray(Image.open(path).convert("RGB"), dtype=float)
        rows, cols = rgb.shape[0] // PANEL[1], rgb.shape[1] // PANEL[0]
        assert rows * PANEL[1] == rgb.shape[0] and cols * PANEL[0] == rgb.shape[1], name
        for r in range(rows):
            for c in range(cols):
                panel = rgb[r * PANEL[1] : (r + 1) * PANEL[1], c * PANEL[0] : (c + 1) * PANEL[0]]
                above_bar = panel[: int(0.8 * PANEL[1])]
                assert _tape_pixels(above_bar).sum() > 0.005 * PANEL[0] * PANEL[1], (name, r, c)


def test_animation_has_a_frame_per_snapshot(run_dir):
    from PIL import Image

    gif = Image.open(run_dir / "figures" / "animation.gif")
    snapshots = list((run_dir / "snapshots").glob("*_[0-9]*.npz"))
    # (a GIF encoder may merge two identical consecutive frames, e.g. the first flattening steps)
    assert len(snapshots) > 5 and len(snapshots) - 2 <= gif.n_frames <= len(snapshots)


def _phases(run_dir):
    """(snapshot files, cells file, phase) of each phase's snapshots, the run's config and axis."""
    from tapecoil.config import load_config
    from tapecoil.hub.frame import HubFrame

    config = load_config(run_dir / "config.toml")
    axis = HubFrame(config.hub.radius, config.tape.h, config.coiling.sense).axis_point
    folder = run_dir / "snapshots"
    sequences = [
        (sorted(folder.glob(f"{phase}_[0-9]*.npz")), folder / f"{phase}_cells.npz", phase)
        for phase in ("coiling", "deployment")
    ]
    return sequences, config, axis


def test_a_phase_keeps_one_camera_for_all_its_frames(run_dir, tmp_path):
    """The animation's and the sequence's frames of a phase are all seen by the same camera, so
    that the hub stays in its place and the scale holds while the tape moves; and the camera
    frames the whole motion (it looks at the middle of the box holding every frame)."""
    from tapecoil.post.render import animate_snapshots, phase_views, render_snapshots, snapshot_grid

    sequences, config, axis = _phases(run_dir)
    cameras = []
    animate_snapshots(sequences, tmp_path / "animation.gif", config, axis, cameras=cameras)
    for files, cells, phase in sequences:
        seen = [used for label, used in cameras if label == phase]
        assert len(seen) == len(files) > 2, phase
        assert all(used == seen[0] for used in seen), phase
        bounds = np.array([snapshot_grid(cells, f, config.tape.R).bounds for f in files])
        (x0, x1), (z0, z1) = (
            (bounds[:, 0].min(), bounds[:, 1].max()),
            (bounds[:, 4].min(), bounds[:, 5].max()),
        )
        _, focal, _, _ = seen[0][0]
        assert x0 < focal[0] < x1 and focal[0] == pytest.approx((x0 + x1) / 2, abs=0.1 * (x1 - x0)), phase
        assert z0 - (x1 - x0) < focal[2] < z1, phase
        # a zoom on the hub region, as a long tape gets: one camera for it too, on the hub's axis
        views = phase_views(list(bounds), axis, config.hub.radius, config.tape.b, zoom=True)
        panels = []
        render_snapshots(
            files[:3],
            cells,
            tmp_path / "zoomed.png",
            config,
            axis,
            ["a", "b", "c"],
            views=views,
            cameras=panels,
        )
        whole, hub = panels[0::2], panels[1::2]
        assert len(whole) == len(hub) == 3
        assert all(c == whole[0] for c in whole) and all(c == hub[0] for c in hub), phase
        assert hub[0][1][0] == pytest.approx(axis[0]) and hub[0] != whole[0], phase


def test_report_ties_numbers_and_pictures_together(run_dir):
    """Every picture is shown, and the validation table has a row per validated quantity of
    summary.json, in its order: its phase, label, computed value and pass mark."""
    import html as html_lib
    import re

    html = (run_dir / "report.html").read_text()
    for name in EXPECTED:
        assert f'src="figures/{name}.png"' in html, name
    assert 'src="figures/animation.gif"' in html
    summary = json.loads((run_dir / "summary.json").read_text())
    tables = re.findall(r"<table>(.*?)</table>", html, flags=re.S)
    validation = next(t for t in tables if "<th>tolerance</th>" in t)
    rows = [re.findall(r"<td([^>]*)>(.*?)</td>", tr) for tr in re.findall(r"<tr>(.*?)</tr>", validation)]
    rows = [r for r in rows if r]  # the header row has no <td>
    assert len(rows) == len(summary["validation"])
    marks = {True: (' class="pass"', "pass"), False: (' class="fail"', "FAIL"), None: ("", "")}
    outcomes = {row["passed"] for row in summary["validation"]}
    assert {True, False} <= outcomes  # this short run has both: the marks are each tested
    for cells, row in zip(rows, summary["validation"], strict=True):
        assert len(cells) == 7, cells
        assert cells[0][1] == row["phase"]
        assert cells[1][1] == html_lib.escape(row["label"])
        computed = row["computed"]
        shown = (
            "-" if computed is None else f"{computed:.5g}" if isinstance(computed, float) else str(computed)
        )
        assert cells[2][1] == shown, row["label"]
        assert cells[6] == marks[row["passed"]], row["label"]


@pytest.mark.slow
def test_report_command_remakes_the_report(run_dir, capsys):
    from tapecoil.app.cli import main

    (run_dir / "report.html").unlink()
    assert main(["report", str(run_dir)]) == 0
    assert (run_dir / "report.html").is_file()
    assert str(run_dir / "report.html") in capsys.readouterr().out
