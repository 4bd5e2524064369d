"""Parameter studies: ``tapecoil sweep sweep.toml``, cases spread over MPI sub-communicators.

A sweep file is a configuration file (the base case: any of its tables, defaults otherwise)
with a ``[sweep]`` table::

    [sweep]
    study = "coiling_tension"      # or "wrapping", "coil" (coiling runs), "run" (coil, stow, deploy)
    ranks_per_case = 1             # the size of each case's sub-communicator

    [sweep.parameters]             # every combination of these values is a case
    "hub.radius_over_R" = [0.5, 0.6, 0.7, 0.8, 0.9]

    [sweep.tension]                # options of the coiling_tension study (coiling.TensionStudy)
    preset = "default"

    [sweep.wrapping]               # options of the wrapping study (wrapping.WrapStudy)
    release = 0.005

Parameters are configuration keys ("tape.h", "coiling.tension", ...) or "hub.radius_over_R",
the hub radius as a fraction of tape.R. Every case's configuration is checked before anything is
computed; in the coil and run studies, rank 0 also warns then of each case's pull below the
tension its hub needs (``Config.coiling_warnings``, the message in the case's run.log too; the
coiling_tension study sets its own pull, T = Eq. 2.6 at r_c + excess, and its own hub angle and tape
length, so it warns of nothing, but each case's configuration, hub_angle included, must still
be valid). Under ``mpirun -n N`` the ranks form N / ranks_per_case groups, and case i runs on group
i mod groups, each into its own results directory ``case-NN-<values>``. Rank 0 then writes the
summary table (sweep_summary.csv, sweep_summary.json) and a plot (sweep.png: the coiling tension,
or the wrapping study's required tension, against r_c/R with Eq. 2.6, the loss-of-uniqueness band
and Eq. 2.9 drawn in; or each validated quantity's ratio to its reference against the first
parameter). The wrapping study (:mod:`tapecoil.phases.wrapping`) also sets its own tape length,
hub angle, pull and mesh.
"""

from __future__ import annotations

import csv
import dataclasses
import importlib
import itertools
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI

from tapecoil.config import Config, ConfigError, config_from_dict
from tapecoil.config.model import hybrid_deployment_need

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

STUDIES = ("coiling_tension", "wrapping", "coil", "run")
# the studies with options of their own: the sweep table that holds them, and their dataclass
STUDY_OPTIONS = {
    "coiling_tension": ("tension", "tapecoil.phases.tension_study", "TensionStudy"),
    "wrapping": ("wrapping", "tapecoil.phases.wrapping", "WrapStudy"),
}
DERIVED = ("hub.radius_over_R",)


@dataclass
class Sweep:
    """A parsed sweep: the study, the base configuration (as a table) and the cases."""

    study: str
    base: dict
    parameters: dict[str, list]
    ranks_per_case: int
    tension: dict
    wrapping: dict = dataclasses.field(default_factory=dict)

    def study_options(self):
        """The options object of the study (TensionStudy or WrapStudy), or None."""
        if self.study not in STUDY_OPTIONS:
            return None
        table, module, name = STUDY_OPTIONS[self.study]
        cls = getattr(importlib.import_module(module), name)
        values = getattr(self, table)
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in values.items()})

    def cases(self) -> list[dict]:
        """Every combination of the parameter values, in order: [{key: value, ...}, ...]."""
        keys = list(self.parameters)
        return [
            dict(zip(keys, values, strict=True)) for values in itertools.product(*self.parameters.values())
        ]

    def config(self, case: dict) -> Config:
        """The configuration of a case (checked: a bad value raises ConfigError naming it)."""
        table = json.loads(json.dumps(self.base))  # a deep copy
        # configuration keys first, then the derived ones (which refer to them)
        for key, value in sorted(case.items(), key=lambda item: item[0] in DERIVED):
            if key == "hub.radius_over_R":
                tape = config_from_dict(json.loads(json.dumps(table))).tape
                key, value = "hub.radius", value * tape.R
            section, name = key.split(".")
            table.setdefault(section, {})[name] = value
        try:
            return config_from_dict(table)
        except ConfigError as err:
            raise ConfigError(f"sweep case {case}: {err}") from None


def load_sweep(path: str | Path) -> Sweep:
    """Read and check a sweep file; every case's configuration is built once here."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise ConfigError(f"sweep file not found: {path}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path} is not valid TOML: {exc}") from None
    table = data.pop("sweep", None)
    if not isinstance(table, dict):
        raise ConfigError(f"{path} has no [sweep] table")
    known = {"study", "ranks_per_case", "parameters", *(table for table, _, _ in STUDY_OPTIONS.values())}
    unknown = set(table) - known
    if unknown:
        raise ConfigError(f"unknown key sweep.{sorted(unknown)[0]} (known: {', '.join(sorted(known))})")
    study = table.get("study", "coiling_tension")
    if study not in STUDIES:
        raise ConfigError(
            f"sweep.study = {study!r} is not allowed: must be one of {', '.join(map(repr, STUDIES))}"
        )
    ranks = table.get("ranks_per_case", 1)
    if not isinstance(ranks, int) or isinstance(ranks, bool) or ranks < 1:
        raise ConfigError(f"sweep.ranks_per_case must be an integer >= 1 (got {ranks!r})")
    parameters = table.get("parameters", {})
    if not parameters or not isinstance(parameters, dict):
        raise ConfigError(
            'sweep.parameters must be a table of lists of values, e.g. "hub.radius_over_R" = [0.5, 0.7]'
        )
    base_keys = {
        f.name: {g.name for g in dataclasses.fields(f.default_factory)} for f in dataclasses.fields(Config)
    }
    for key, values in parameters.items():
        if not isinstance(values, list) or not values:
            raise ConfigError(f'sweep.parameters."{key}" must be a non-empty list of values')
        section, _, name = key.partition(".")
        if key not in DERIVED and name not in base_keys.get(section, ()):
            raise ConfigError(
                f'sweep.parameters."{key}" is neither a configuration key (section.key) nor one of {DERIVED}'
            )
    options = {}
    for name, (key, module, cls_name) in STUDY_OPTIONS.items():
        values = table.get(key, {})
        if not isinstance(values, dict):
            raise ConfigError(f"sweep.{key} must be a table")
        fields = {f.name for f in dataclasses.fields(getattr(importlib.import_module(module), cls_name))}
        for option in values:
            if option not in fields:
                raise ConfigError(f"unknown key sweep.{key}.{option} (known: {', '.join(sorted(fields))})")
        if values and study != name:
            raise ConfigError(f"sweep.{key} is for study = {name!r} only")
        options[key] = values
    sweep = Sweep(study, data, parameters, ranks, options["tension"], options["wrapping"])
    if study in STUDY_OPTIONS:
        sweep.study_options().check()
    config_from_dict(json.loads(json.dumps(data)))  # the base case itself
    for case in sweep.cases():
        config = sweep.config(case)
        need = hybrid_deployment_need(config) if study == "run" else None
        if need is not None:  # the run deploys: refused here, not after the cases before it
            raise ConfigError(f"sweep case {case}: {need}")
    return sweep


def case_name(index: int, case: dict) -> str:
    values = ",".join(
        f"{key.split('.')[-1]}={value:g}" if isinstance(value, float) else f"{key.split('.')[-1]}={value}"
        for key, value in case.items()
    )
    return f"case-{index:02d}-{values}"


def run_sweep(sweep: Sweep, directory: str | Path, comm=MPI.COMM_WORLD, progress: bool = True) -> dict:
    """Run every case on its group of ranks, then write the summary table and plot (rank 0)."""
    directory = Path(directory)
    if comm.size % sweep.ranks_per_case:
        raise ConfigError(
            f"sweep.ranks_per_case = {sweep.ranks_per_case} does not divide the {comm.size} MPI ranks"
        )
    groups = comm.size // sweep.ranks_per_case
    group = comm.rank // sweep.ranks_per_case
    sub = comm.Split(color=group, key=comm.rank)
    if comm.rank == 0:
        directory.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    cases = sweep.cases()
    if sweep.study not in STUDY_OPTIONS:
        from tapecoil.app.checks import warn_before_coiling
        from tapecoil.phases.coiling import check_free_end_room

        configs = [sweep.config(case) for case in cases]
        for case, config in zip(cases, configs, strict=True):  # before any case is computed
            try:
                check_free_end_room(config)  # on every rank: it raises
            except ConfigError as err:
                raise ConfigError(f"sweep case {case}: {err}") from None
        if comm.rank == 0:
            for case, config in zip(cases, configs, strict=True):
                warn_before_coiling(config, prefix=f"sweep case {case}: ")
    mine = [(i, case) for i, case in enumerate(cases) if i % groups == group]
    bar = None
    if progress and comm.rank == 0:
        from tqdm import tqdm

        bar = tqdm(total=len(mine), desc=f"sweep (group 0 of {groups})", unit="case", disable=None)
    for i, case in mine:
        _run_case(sweep, i, case, directory / case_name(i, case), sub)
        if bar is not None:
            bar.update()
    if bar is not None:
        bar.close()
    sub.Free()
    comm.barrier()
    summary = None
    if comm.rank == 0:
        summary = _summarise(sweep, cases, directory, groups)
    return comm.bcast(summary, root=0)


def _run_case(sweep: Sweep, index: int, case: dict, directory: Path, comm) -> None:
    config = sweep.config(case)
    if sweep.study == "coiling_tension":
        from tapecoil.app.results import prepare_directory
        from tapecoil.core.output import write_csv
        from tapecoil.phases.tension_study import coiling_tension

        prepare_directory(directory, config, comm)
        result = coiling_tension(config, comm, sweep.study_options())
        write_csv(directory / "coiling_history.csv", result.pop("history"), comm)
        if comm.rank == 0:
            (directory / "summary.json").write_text(
                json.dumps({"case": case, "coiling_tension": result}, indent=2)
            )
        return
    if sweep.study == "wrapping":
        from tapecoil.app.wrapping import write_wrapping_case

        write_wrapping_case(config, sweep.study_options(), directory, comm, case)
        return
    from tapecoil.app.checks import warn_before_coiling
    from tapecoil.app.pipeline import run

    # the console had it from run_sweep; the case's own log has it here
    warn_before_coiling(config, directory, comm, prefix=f"sweep case {case}: ", console=False)
    phases = ("coiling",) if sweep.study == "coil" else ("coiling", "deployment")
    summary = run(config, directory, phases=phases, comm=comm, progress=False, report=False, command="sweep")
    if comm.rank == 0:
        summary["case"] = case
        (directory / "summary.json").write_text(json.dumps(summary, indent=2))


def _summarise(sweep: Sweep, cases: list[dict], directory: Path, groups: int) -> dict:
    rows = []
    for i, case in enumerate(cases):
        summary = json.loads((directory / case_name(i, case) / "summary.json").read_text())
        row = {"case": i, **case}
        if sweep.study == "coiling_tension":
            t = summary["coiling_tension"]
            row.update(
                {
                    "ratio": t["ratio"],
                    "coiling_tension": t["computed"],
                    "eq_2_6": t["reference"],
                    "error": t["error"],
                    "eq_2_9": t["tension_dominated_eq_2_9"],
                    "spread": t["spread"],
                    # the coil's own sections, against the plate with its free edges
                    "coil_section_tension": t.get("coil_section_tension", ""),
                    "eq_2_6_with_edges": t.get("reference_with_edges", ""),
                    "coil_energy_per_length": t.get("coil_energy_per_length", ""),
                    "edge_layer_energy_per_length": t.get("edge_layer_energy_per_length", ""),
                    "wall_time": t["wall_time"],
                }
            )
        elif sweep.study == "wrapping":
            w = summary["wrapping"]
            row.update(
                {
                    k: w[k]
                    for k in (
                        "ratio",
                        "regime",
                        "required_tension",
                        "lift_off_tension",
                        "eq_2_6",
                        "eq_2_9",
                        "max_folds",
                        "fold_radius_min",
                        "fold_radius_max",
                        "completed",
                        "steps",
                        "newton_iterations",
                        "dofs",
                        "wall_time",
                    )
                }
            )
        else:
            row["completed"] = summary["completed"]
            for v in summary["validation"]:
                row[f"{v['phase']}.{v['quantity']}"] = v["computed"]
                row[f"{v['phase']}.{v['quantity']}.reference"] = v["reference"]
                row[f"{v['phase']}.{v['quantity']}.error"] = v["error"]
        rows.append(row)
    with (directory / "sweep_summary.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    out = {"study": sweep.study, "parameters": sweep.parameters, "groups": groups, "cases": rows}
    (directory / "sweep_summary.json").write_text(json.dumps(out, indent=2))
    out["plot"] = str(_plot(sweep, rows, directory))
    return out


def _against_ratio(ax, rows: list[dict], key: str, fmt: str, label: str, **style) -> None:
    """One column of the rows against r_c/R."""
    ax.plot([r["ratio"] for r in rows], [r[key] for r in rows], fmt, label=label, **style)


def _plot(sweep: Sweep, rows: list[dict], directory: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    if sweep.study in STUDY_OPTIONS:
        from tapecoil.post.plots import draw_regime_laws

        ratio = np.array([r["ratio"] for r in rows])
        draw_regime_laws(ax, sweep.config({}), (0.9 * ratio.min(), 1.1 * ratio.max()))
    if sweep.study == "coiling_tension":
        ax.errorbar(
            ratio,
            [r["coiling_tension"] for r in rows],
            yerr=[r["spread"] for r in rows],
            fmt="o",
            capsize=3,
            label="shell: T - N at the root's clamp, mean over the steady phase (bar: spread)",
        )
        sections = [r for r in rows if r["coil_section_tension"] != ""]
        if sections:
            _against_ratio(
                ax,
                sections,
                "eq_2_6_with_edges",
                "k-.",
                "Eq. 2.6 + the free edges' layers (theory.edge_layer)",
            )
            _against_ratio(
                ax,
                sections,
                "coil_section_tension",
                "s",
                "shell: T - N across the coil's own sections (steady stretch)",
                mfc="none",
            )
        ax.set(xlabel="r_c / R", ylabel="coiling tension [N]", title="steady coiling tension")
    elif sweep.study == "wrapping":
        done = [r for r in rows if r["required_tension"] is not None]
        _against_ratio(
            ax,
            done,
            "required_tension",
            "o",
            "shell: force on the end when the centre line conforms over 305 deg (wrapping)",
        )
        _against_ratio(
            ax,
            done,
            "lift_off_tension",
            "o",
            "shell: the same, less the axial force the clamped root holds (T - N)",
            mfc="none",
        )
        for r in done:
            if r["max_folds"]:
                ax.annotate(
                    f"{r['max_folds']}",
                    (r["ratio"], r["required_tension"]),
                    fontsize=7,
                    xytext=(3, 3),
                    textcoords="offset points",
                )
        ax.set(
            xlabel="r_c / R",
            ylabel="tension [N]",
            title="tension needed to wrap (number: most folds seen)",
            yscale="symlog",
        )
    if sweep.study not in STUDY_OPTIONS:
        key = next(iter(sweep.parameters))
        x = np.array([r[key] for r in rows], dtype=float)
        quantities = sorted({k[: -len(".reference")] for r in rows for k in r if k.endswith(".reference")})
        for q in quantities:
            ratios = [
                r[q] / r[f"{q}.reference"] if r.get(q) is not None and r.get(f"{q}.reference") else math.nan
                for r in rows
            ]
            ax.plot(x, ratios, "o-", label=q)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set(xlabel=key, ylabel="computed / reference", title=f"sweep: {sweep.study}")
    ax.grid(alpha=0.3)
    if sweep.study == "wrapping":  # its points fill the plot: the legend goes below it
        fig.set_size_inches(7.5, 6.0)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    else:
        ax.legend(fontsize=7)
    fig.tight_layout()
    path = directory / "sweep.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path
