"""Equilibrium paths followed through their instabilities, as files: a CSV of the points and a
plot with the stable and unstable states and the located critical points (matplotlib).

The tape spring's moment-rotation curves (:mod:`tapecoil.verification.moment_rotation`) and Sze's
roof's load-deflection curves (:mod:`tapecoil.verification.roof`). Serial: the caller writes on
one rank.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

# the branches of a moment-rotation curve, in the order they are followed
BRANCH_LABELS = {
    "primary": "primary branch",
    "fold": "snap, then the fold stepped",
    "return": "return (arc length)",
}
SENSE_COLOURS = {"opposite": "tab:blue", "equal": "tab:red"}


def write_rows(path: Path, header: list[str], rows) -> Path:
    """A CSV of ``rows`` under ``header``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        for row in rows:
            writer.writerow(["" if isinstance(v, float) and math.isnan(v) else v for v in row])
    return path


def _stable_unstable(ax, x, y, stable, colour, label):
    """A branch drawn as a line, its unstable states marked over it."""
    ax.plot(x, y, "-", color=colour, lw=1.2, label=label)
    ux = [a for a, s in zip(x, stable, strict=True) if s is False]
    uy = [b for b, s in zip(y, stable, strict=True) if s is False]
    if ux:
        ax.plot(ux, uy, "o", ms=3, mfc="none", color=colour, alpha=0.8)


def moment_rotation_files(curves: dict, directory: Path, title: str = "") -> list[Path]:
    """``moment_rotation.csv`` (every state of every sense: sense, branch, phi [rad], M [N m],
    M / the fold moment, stable, the eigenvalue nearest zero) and ``moment_rotation.png`` (M
    against phi, each sense's branches, its unstable states circled, its critical points and its
    steady fold moment's reference) into ``directory``; ``curves``: sense -> the dict of
    :func:`~tapecoil.verification.moment_rotation.moment_rotation_curve`."""
    directory = Path(directory)
    rows = []
    for sense, c in curves.items():
        ref = c["fold_moment_reference"]
        for part, phi, M, stable, eig in c["rows"]:
            rows.append((sense, part, phi, M, M / ref, "" if stable is None else int(stable), eig))
    csv_path = write_rows(
        directory / "moment_rotation.csv",
        ["sense", "branch", "rotation_rad", "moment_Nm", "moment_over_fold_moment", "stable", "eigenvalue"],
        rows,
    )
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    snaps = [
        k["rotation"]
        for c in curves.values()
        for k in c["critical"]
        if k.get("branch", "primary") == "primary"
    ]
    for sense, c in curves.items():
        colour = SENSE_COLOURS.get(sense, "k")
        ref = c["fold_moment_reference"]
        for ax, scale in ((axes[0], 1.0), (axes[1], 1.0 / ref)):
            for part, alpha in (("primary", 1.0), ("fold", 0.5), ("return", 0.8)):
                pts = [r for r in c["rows"] if r[0] == part]
                if not pts:
                    continue
                _stable_unstable(
                    ax,
                    [r[1] for r in pts],
                    [r[2] * scale for r in pts],
                    [r[3] for r in pts],
                    colour,
                    f"{sense}: {BRANCH_LABELS[part]}" if ax is axes[0] else None,
                )
                ax.lines[-1].set_alpha(alpha)
            for k in c["critical"]:
                marker = "v" if k["kind"] == "limit" else "s"
                ax.plot(k["rotation"], k["moment"] * scale, marker, color=colour, ms=5, mec="k", mew=0.5)
        axes[1].axhline(1.0, color=colour, ls=":", lw=1)
        if "fold_moment_with_edges" in c:
            axes[1].axhline(c["fold_moment_with_edges"] / ref, color=colour, ls="--", lw=0.8)
    if snaps:
        axes[0].set_xlim(0.0, 1.5 * max(snaps))
    axes[0].set_title("around the snaps")
    axes[0].set_ylabel("moment M [N m]")
    axes[1].set_ylim(0.0, 2.0)
    axes[1].set_title(
        "M over alpha (sqrt(D11 D22) +- D12): dotted 1, dashed with the edge layers", fontsize=9
    )
    axes[1].set_ylabel("M / fold moment [-]")
    for ax in axes:
        ax.set_xlabel("end rotation phi [rad]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(
        (title + "\n" if title else "")
        + "circles: unstable states (end rotation held); triangles: limit points; squares: bifurcations",
        fontsize=9,
    )
    fig.tight_layout()
    png = directory / "moment_rotation.png"
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return [csv_path, png]


def roof_files(label: str, result: dict, reference: tuple[float, float], directory: Path) -> list[Path]:
    """``<label>.csv`` (every point: load P, deflection w under it, stable, the eigenvalue
    nearest zero) and ``<label>.png`` (P against w, unstable states circled, the located limit
    points, Sze's limit load dashed) into ``directory``; ``result``: the dict of
    :func:`~tapecoil.verification.roof.roof_curve`; ``reference``: (Sze's limit load, the
    deflection of their table's point of largest load)."""
    directory = Path(directory)
    csv_path = write_rows(
        directory / f"{label}.csv",
        ["load_P", "deflection_w", "stable", "eigenvalue"],
        [(P, w, "" if s is None else int(s), e) for P, w, s, e in result["curve"]],
    )
    fig, ax = plt.subplots(figsize=(6, 4.4))
    P = [p[0] for p in result["curve"]]
    w = [p[1] for p in result["curve"]]
    _stable_unstable(ax, w, P, [p[2] for p in result["curve"]], "tab:blue", f"tapecoil ({result['mesh']})")
    for kind, load, deflection, *_ in result["critical"]:
        ax.plot(deflection, load, "v" if kind == "limit" else "s", color="tab:blue", ms=6, mec="k", mew=0.5)
    ax.axhline(
        reference[0], color="k", ls="--", lw=0.8, label=f"Sze et al. 2004: limit load {reference[0]:.1f}"
    )
    ax.plot(reference[1], reference[0], "k+", ms=9, label="Sze's point of largest load")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("deflection under the load w")
    ax.set_ylabel("load P")
    ax.set_title(f"{label}: circles unstable (load held), triangles limit points", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = directory / f"{label}.png"
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return [csv_path, png]
