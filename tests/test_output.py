"""ParaView output: the offset field rebuilds the 3D surface; no NaN is ever written."""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from tapecoil.config import load_config
from tapecoil.core.output import NonFiniteStateError, ShellWriter, write_csv
from tapecoil.geometry.meshes import MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.shell import NaghdiShell, ShellMaterial


@pytest.fixture
def model():
    cfg = load_config()
    strip = create_strip_mesh(MPI.COMM_WORLD, StripGeometry.from_config(cfg), MeshResolution(2, 6))
    return NaghdiShell(strip, ShellMaterial(cfg.tape.E, cfg.tape.nu, cfg.tape.h))


def test_offset_rebuilds_the_reference_surface(model, tmp_path):
    path = tmp_path / "shell.bp"
    with ShellWriter(model, path) as writer:
        writer.write(0.0)
        offset = writer.fields[0][0]
        xi = offset.function_space.tabulate_dof_coordinates()
        X = xi + offset.x.array.reshape(-1, 3)  # what Warp By Vector shows
        assert np.allclose(X.T, model.strip.geometry.phi0(xi.T), atol=1e-14)
    assert path.exists()


def test_non_finite_state_is_refused(model, tmp_path):
    writer = ShellWriter(model, tmp_path / "bad.bp")
    model.q.x.array[0] = np.nan
    with pytest.raises(NonFiniteStateError):
        writer.write(1.0)
    writer.close()


def test_csv(tmp_path):
    write_csv(tmp_path / "h.csv", [{"step": 1, "energy": 0.5}, {"step": 2, "energy": 0.25}])
    assert (tmp_path / "h.csv").read_text().splitlines() == ["step,energy", "1,0.5", "2,0.25"]
    with pytest.raises(NonFiniteStateError):
        write_csv(tmp_path / "n.csv", [{"energy": float("nan")}])


def _outcome(call):
    """None if ``call()`` returns, else the type and message of what it raised."""
    try:
        call()
    except Exception as exc:
        return f"{type(exc).__name__}: {exc}"
    return None


def test_csv_unwritable_path_is_an_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("a file where a directory should be")
    for comm in (None, MPI.COMM_WORLD):
        with pytest.raises(OSError):
            write_csv(blocker / "h.csv", [{"step": 1}], comm)


@pytest.mark.mpi
def test_csv_errors_reach_every_rank(tmp_path):
    """Rank 0 writes; when it cannot, every rank raises the same error instead of walking on
    into the next collective operation and waiting there for ever."""
    comm = MPI.COMM_WORLD
    directory = Path(comm.bcast(str(tmp_path), root=0))
    blocker = directory / "file"
    if comm.rank == 0:
        blocker.write_text("a file where a directory should be")
    comm.barrier()
    rows = [{"step": 1, "energy": 0.5}]
    for path, rows_, kind in (
        (blocker / "h.csv", rows, "FileExistsError"),  # mkdir of a directory where a file is
        (directory / "n.csv", [{"energy": float("nan")}], "NonFiniteStateError"),
    ):
        # the outcomes are gathered, not raised at once, so that a rank that did not raise cannot
        # leave the others waiting: the test fails on every rank instead
        outcomes = comm.allgather(_outcome(lambda p=path, r=rows_: write_csv(p, r, comm)))
        assert outcomes[0] is not None and outcomes[0].startswith(kind), outcomes
        assert outcomes == [outcomes[0]] * comm.size
    assert not (directory / "n.csv").exists()
    # and a good history is written once, by rank 0, with every rank returning
    assert comm.allgather(_outcome(lambda: write_csv(directory / "h.csv", rows, comm))) == [None] * comm.size
    assert (directory / "h.csv").read_text().splitlines() == ["step,energy", "1,0.5"]


def test_render_is_a_picture_of_the_shell(model, tmp_path):
    """The off-screen render shows the shell: not a blank window."""
    import numpy as np
    from PIL import Image

    from tapecoil.post.render import render_shell

    path = render_shell(model, tmp_path / "shell.png", scalar=model.curvatures()[1], name="kappa_trans")
    image = np.asarray(Image.open(path).convert("L"), dtype=float)
    assert image.shape[0] > 100 and image.shape[1] > 100
    assert (image < 250).mean() > 0.01  # enough non-white pixels: the shell is drawn
    assert image.std() > 5
