"""A wrapping case's results directory: the force-extension history, the summary, the pictures."""

from __future__ import annotations

import json
from pathlib import Path

from mpi4py import MPI

from tapecoil.app.results import prepare_directory
from tapecoil.config import Config
from tapecoil.core.output import write_csv
from tapecoil.phases.runner import LOG
from tapecoil.phases.wrapping import WrapStudy, wrapping_tension


def write_wrapping_case(
    config: Config, study: WrapStudy, directory: str | Path, comm=MPI.COMM_WORLD, case=None
) -> dict:
    """Run :func:`~tapecoil.phases.wrapping.wrapping_tension` into ``directory`` (collective).

    Writes config.toml (the case as given; the study sets the tape's length, the hub angle, the
    pull and the mesh), wrap_history.csv (a row per step of the release and the pull),
    summary.json (``wrapping``: the required tension, Eq. 2.6 and 2.9, the folds, the run's
    figures), figures/force_extension.png and, on one rank, figures/folds.png: the tape in the
    state with the most folds, coloured by its longitudinal curvature.
    """
    directory = prepare_directory(directory, config, comm)
    result = wrapping_tension(config, comm, study)
    history, model = result.pop("history"), result.pop("model")
    fold_state, fold_state_at = result.pop("fold_state"), result.pop("fold_state_at")
    rows = [
        {k: ";".join(f"{x:.6g}" for x in v) if isinstance(v, list) else v for k, v in row.items()}
        for row in history
    ]
    if rows:
        write_csv(directory / "wrap_history.csv", rows, comm)
    if comm.rank == 0:
        (directory / "summary.json").write_text(json.dumps({"case": case, "wrapping": result}, indent=2))
        figures = directory / "figures"
        figures.mkdir(exist_ok=True)
        from tapecoil.post.plots import force_extension

        force_extension(
            history, result["required_tension"], study.conform_angle, figures / "force_extension.png"
        )
    if fold_state is not None and comm.size == 1:
        from tapecoil.post.render import render_on_hub

        model.model.q.x.array[:] = fold_state
        try:
            render_on_hub(
                model.model,
                model.frame.axis_point,
                model.config,
                directory / "figures" / "folds.png",
                f"r_c/R = {result['ratio']:.3g}: the most folds of the release, end let back "
                f"{-1e3 * fold_state_at:.2g} mm",
            )
        except Exception as err:  # a picture is not worth the case: say why it is missing
            LOG.warning("wrapping: the folds' picture was not drawn (%s)", err)
    if not result["completed"]:
        LOG.warning("wrapping case %s: %s", case, result["message"])
    return result
