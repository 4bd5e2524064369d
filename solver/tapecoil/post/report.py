"""The report of a results directory: figures, renders, an animation and report.html.

``tapecoil report DIR`` (and the end of ``tapecoil run``, ``coil`` and ``deploy``) reads what the
run wrote and makes, in DIR/figures, the matplotlib figures of :mod:`tapecoil.post.plots`, PyVista
renders of the coiling and the deployment from the gathered surface snapshots, an animated GIF of
the whole run, and DIR/report.html, which ties the validation table, the run's figures and the
pictures together (a browser is all it needs). Serial (rank 0).
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from tapecoil.config import load_config
from tapecoil.hub.frame import HubFrame
from tapecoil.post import plots

CAPTIONS = {
    "coiling_energies": "Stored energy against hub angle, with the plate estimate w(r) b for the "
    "length actually coiled (physics.md Sec. 3), and its parts.",
    "coiling_forces": "The pull held at the free end and the coiling tension T - N, at the root "
    "against Eq. 2.6 on the bare hub and on the outer turn against Eq. 4.5 at the coil's growing "
    "radius; the hub torque from the energy balance against steady coiling.",
    "coil_radius": "Outer coil radius against r_hub + h theta / 2 pi, and the radius of each turn "
    "against the spiral r_hub + h/2 + n h.",
    "coil_profiles": "The stowed coil: curvatures and surface stresses along the coiled length and "
    "across the width, against plate theory (physics.md Sec. 4).",
    "deployment_lambda": "Deployed fraction against Seffen and Pellegrino's law (Eq. 2.20) and the "
    "modified ODE from the simulation's own lambda0, with mu and with the coil's plate energy.",
    "deployment_energies": "Energy balance of the deployment. The remainder is the scheme's numerical "
    "dissipation less the contact energy the winding angles' update adds between steps (and the "
    "converged residual's work, negligible).",
    "deployment_root_loads": "The force and torque the tape exerts on the hub through its root, the "
    "attachment's reaction: what the hub and the spacecraft interface carry.",
    "payout_forces": "A driven hub paying the tape out with the pull held: the coiling tension T - N "
    "on the outer turn against Eq. 4.5 (the coil's growing radius) and at the root against Eq. 2.6; "
    "the hub torque from the root's reactions against steady coiling.",
    "coiling_sequence": "Coiling, four snapshots; colour: longitudinal curvature times R.",
    "stowed": "The stowed coil after the last step.",
    "deployment_sequence": "Deployment, four snapshots.",
}


def _snapshots(directory: Path, phase: str) -> tuple[list[Path], Path | None]:
    folder = directory / "snapshots"
    cells = folder / f"{phase}_cells.npz"
    if not cells.is_file():
        return [], None
    files = sorted(p for p in folder.glob(f"{phase}_[0-9]*.npz"))
    return files, cells


def _spread(files: list[Path], n: int) -> list[Path]:
    if len(files) <= n:
        return files
    return [files[i] for i in np.rint(np.linspace(0, len(files) - 1, n)).astype(int)]


def renders(directory: Path) -> list[Path]:
    """PNG renders and the GIF from the snapshots (needs PyVista and an X server or Xvfb)."""
    from tapecoil.post.render import animate_snapshots, phase_views, render_snapshots, snapshot_grid

    config = load_config(directory / "config.toml")
    axis = HubFrame(config.hub.radius, config.tape.h, config.coiling.sense).axis_point
    figures = directory / "figures"
    figures.mkdir(exist_ok=True)
    out = []
    sequences, views = [], []
    for phase, unit in (("coiling", "rad"), ("deployment", "s")):
        files, cells = _snapshots(directory, phase)
        if not files:
            continue
        frames, chosen = _spread(files, 120), _spread(files, 4)
        # one camera for the phase, from every frame the animation and the sequence show: they
        # then share the hub's place and the scale
        view = phase_views(
            [snapshot_grid(cells, f, config.tape.R).bounds for f in sorted({*frames, *chosen})],
            axis,
            config.hub.radius,
            config.tape.b,
        )
        sequences.append((frames, cells, phase))
        views.append(view)
        times = [float(np.load(f)["t"]) for f in chosen]
        titles = [
            "flattening" if phase == "coiling" and t == 0 else f"{phase}: {t:.4g} {unit}" for t in times
        ]
        shape = (2, 2) if len(chosen) == 4 else (1, len(chosen))
        out.append(
            render_snapshots(
                chosen, cells, figures / f"{phase}_sequence.png", config, axis, titles, shape, views=view
            )
        )
        if phase == "coiling":
            last = files[-1]
            title = f"stowed: hub angle {float(np.load(last)['t']):.4g} rad"
            out.append(render_snapshots([last], cells, figures / "stowed.png", config, axis, [title]))
    if sequences:
        out.append(animate_snapshots(sequences, figures / "animation.gif", config, axis, views=views))
    return out


def _number(value, digits=5) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return html.escape(str(value))


def _validation_table(rows: list[dict]) -> str:
    lines = [
        "<table><tr><th>phase</th><th>quantity</th><th>computed</th><th>reference</th>"
        "<th>error</th><th>tolerance</th><th></th></tr>"
    ]
    for r in rows:
        if r.get("bound") == "lower" and r["tolerance"] is None:  # a reading without its bound
            error, tol = "-", "reported"
        elif r.get("bound") == "lower":  # the computed value must reach the reference
            error = "-" if r["error"] is None else ("0" if r["error"] == 0 else _number(r["error"], 2))
            tol = "at least the reference"
        else:
            error = "-" if r["error"] is None else f"{r['error']:.2%}"
            tol = "reported" if r["tolerance"] is None else f"{r['tolerance']:.1%}"
        mark = {True: '<td class="pass">pass</td>', False: '<td class="fail">FAIL</td>', None: "<td></td>"}
        lines.append(
            f"<tr><td>{r['phase']}</td><td>{html.escape(r['label'])}</td><td>{_number(r['computed'])}</td>"
            f"<td>{_number(r['reference'])}</td><td>{error}</td><td>{tol}</td>{mark[r['passed']]}</tr>"
        )
    lines.append("</table>")
    return "\n".join(lines)


def _run_table(summary: dict) -> str:
    lines = [
        "<table><tr><th>phase</th><th>state</th><th>mesh</th><th>DOFs</th><th>ranks</th><th>steps</th>"
        "<th>Newton iterations</th><th>wall time</th></tr>"
    ]
    for phase in ("coiling", "deployment", "payout"):
        if phase not in summary:
            continue
        p, run = summary[phase], summary[phase]["run"]
        state = "completed" if p["completed"] else html.escape(p["message"] or "stopped")
        name = f"{phase} ({plots.model_name(run)})"
        lines.append(
            f"<tr><td>{name}</td><td>{state}</td><td>{run['mesh']}</td><td>{run['dofs']:,}</td>"
            f"<td>{run['ranks']}</td><td>{run['steps']}</td><td>{run['newton_iterations']:,}</td>"
            f"<td>{run['wall_time']:.1f} s</td></tr>"
        )
    lines.append("</table>")
    # how a model computed a phase, in its own words (the hybrid: what the full shell took from it)
    for phase in ("coiling", "deployment", "payout"):
        account = summary.get(phase, {}).get("run", {}).get("account")
        if account:
            lines.append(f"<p>{html.escape(account)}</p>")
    return "\n".join(lines)


def _figure(path: Path, directory: Path) -> str:
    caption = html.escape(CAPTIONS.get(path.stem, ""))
    src = html.escape(str(path.relative_to(directory)))
    return f'<figure><img src="{src}" alt="{path.stem}"><figcaption>{caption}</figcaption></figure>'


STYLE = """
body { font-family: sans-serif; max-width: 1250px; margin: 2em auto; color: #222; }
table { border-collapse: collapse; margin: 1em 0; }
td, th { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
td:nth-child(2), th:nth-child(2) { text-align: left; }
.pass { color: #176117; font-weight: bold; } .fail { color: #b00000; font-weight: bold; }
figure { margin: 1.5em 0; } img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #555; }
"""


def write_report(directory: str | Path, pictures: bool = True) -> Path:
    """Figures (and, with ``pictures``, the renders and GIF) and report.html; returns its path."""
    directory = Path(directory)
    summary = json.loads((directory / "summary.json").read_text())
    figures = plots.all_figures(directory)
    if pictures:
        figures += renders(directory)
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>tapecoil report</title>",
        f"<style>{STYLE}</style></head><body>",
        f"<h1>tapecoil {html.escape(summary['tapecoil'])}: {html.escape(directory.name)}</h1>",
        "<p>Coiling and deployment of a tape spring, computed against the analytic theory of the "
        "physics brief (thesis <i>Coiling and deployment mechanics of tape-springs</i>; Seffen and "
        f"Pellegrino 1999). State: <b>{'completed' if summary['completed'] else 'not completed'}</b>"
        + (f", interrupted ({html.escape(summary['interrupted'])})" if summary.get("interrupted") else "")
        + ". Configuration: <a href='config.toml'>config.toml</a>; log: <a href='run.log'>run.log</a>.</p>",
        "<h2>Run</h2>",
        _run_table(summary),
        "<h2>Validation</h2>",
        "<p>Every validated quantity against its reference, with the tolerance it is held to "
        "('reported': no pass mark). Why each tolerance is what it is, from the physics and the "
        "literature, is recorded with it in summary.json ('basis'). Definitions: docs/notes/coiling.md, "
        "docs/notes/deployment.md.</p>",
        _validation_table(summary["validation"]),
        "<h2>Pictures</h2>",
    ]
    order = [*CAPTIONS, "animation"]
    for path in sorted(figures, key=lambda p: order.index(p.stem) if p.stem in order else len(order)):
        if path.suffix == ".gif":
            parts.append("<h2>Animation</h2>")
        parts.append(_figure(path, directory))
    parts.append(
        "<h2>Files</h2><p>Histories: coiling_history.csv, deployment_history.csv; ParaView: coiling.bp, "
        "deployment.bp (Warp By Vector with <code>offset</code>); checkpoints: stowed/, deployed/; "
        "summary.json.</p></body></html>"
    )
    path = directory / "report.html"
    path.write_text("\n".join(parts))
    return path
