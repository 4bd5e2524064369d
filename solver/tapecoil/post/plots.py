"""Pictures of a results directory (matplotlib), each computed quantity drawn against the theory.

Every function reads the files a run wrote (histories, coiled_cells.csv, summary.json,
config.toml), draws one figure into ``directory/figures`` and returns its path, or None when the
run has no data for it (a coiling-only run has no deployment pictures). Serial; no MPI.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from tapecoil import theory
from tapecoil.config import load_config


def read_history(path: Path) -> dict[str, np.ndarray] | None:
    """A history CSV as columns (numbers; empty cells are NaN, text columns kept as text)."""
    if not path.is_file():
        return None
    with path.open() as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return None
    out = {}
    for key in rows[0]:
        values = [r[key] for r in rows]
        try:
            out[key] = np.array([float(v) if v != "" else np.nan for v in values])
        except ValueError:
            out[key] = np.array(values)
    return out


def _setup(directory: Path):
    config = load_config(directory / "config.toml")
    summary = json.loads((directory / "summary.json").read_text())
    figures = directory / "figures"
    figures.mkdir(exist_ok=True)
    return config, summary, figures


def _save(fig, path: Path) -> Path:
    for ax in fig.axes:
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _coiling_rows(directory: Path):
    h = read_history(directory / "coiling_history.csv")
    if h is None:
        return None
    keep = h["phase"] == "coil"
    return {k: v[keep] for k, v in h.items()}


def coiling_energies(directory: Path) -> Path | None:
    """Membrane, bending, shear and contact energy against hub angle, with the plate estimate."""
    h = _coiling_rows(directory)
    if h is None or len(h["hub_angle"]) == 0:
        return None
    config, _, figures = _setup(directory)
    tp, r_hub = config.tape, config.hub.radius
    angle = h["hub_angle"]
    plate = [
        theory.stored_energy(
            theory.rotation_for_coiled_length(s, r_hub, tp.h),
            r_hub,
            tp.h,
            tp.R,
            tp.alpha,
            config.wall.bending,
            config.coiling.sense,
        )
        for s in h["coiled_length"]
    ]
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    ax[0].plot(angle, h["strain_energy"], label="strain energy, whole tape")
    ax[0].plot(angle, plate, "--", label="plate estimate w(r) b x coiled length (physics.md Sec. 3)")
    ax[0].set(xlabel="hub angle [rad]", ylabel="energy [J]", title="stored energy")
    for key, label in (
        ("bending_energy", "bending"),
        ("membrane_energy", "membrane"),
        ("shear_energy", "transverse shear"),
        ("contact_energy_hub", "contact, hub"),
        ("contact_energy_coil", "contact, coil on coil"),
    ):
        if key in h:  # the hybrid's history has the whole energy alone
            ax[1].semilogy(angle, np.maximum(h[key], 1e-12), label=label)
    ax[1].set(xlabel="hub angle [rad]", ylabel="energy [J]", title="energy parts (log scale)")
    return _save(fig, figures / "coiling_energies.png")


def model_name(run: dict) -> str:
    """The model a phase's rows come from, for the legends: the tag its summary's run figures
    carry (``run``, as summary.json holds them); the full shell writes none."""
    return run.get("model") or "shell"


def coiling_forces(directory: Path) -> Path | None:
    """Tension at the free end, coiling tension T - N against Eq. 2.6 (and, on the outer turn,
    against Eq. 4.5 and Eq. 2.6 with the free edges' share), hub torque against steady coiling."""
    h = _coiling_rows(directory)
    if h is None or len(h["hub_angle"]) == 0:
        return None
    config, summary, figures = _setup(directory)
    tp, r_hub, T = config.tape, config.hub.radius, config.coiling.tension
    model = model_name(summary.get("coiling", {}).get("run", {}))
    angle = h["hub_angle"]
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    ax[0].plot(angle, h["tension"], label="pull held at the free end")
    ax[0].plot(angle, h["coiling_tension"], label="coiling tension T - N (axial force N into the root)")
    eq26 = theory.coiling_tension_bending(config.wall.bending, tp.alpha, tp.R, r_hub)
    ax[0].axhline(eq26, color="k", ls="--", lw=1, label=f"Eq. 2.6, r_c = r_hub: {eq26:.3f} N")
    if "coiling_tension_outer" in h:  # read across the outer turn's sections
        ax[0].plot(angle, h["coiling_tension_outer"], label="coiling tension T - N on the outer turn")
        ax[0].plot(angle, h["eq_4_5"], "k:", label="Eq. 4.5, the coil's mid-surface radius rho(lambda)")
        if "eq_2_6_edges_outer" in h and np.isfinite(h["eq_2_6_edges_outer"]).any():
            ax[0].plot(
                angle, h["eq_2_6_edges_outer"], "k-.", label="Eq. 2.6 + the free edges' share, outer turn"
            )
    elif "coiled_length" in h:
        growing = theory.coiling_tension_growing(
            1.0 - h["coiled_length"] / tp.L, config.wall.bending, tp.alpha, tp.R, r_hub, tp.h, tp.L
        )
        ax[0].plot(angle, growing["bending"], "k:", label="Eq. 4.5, the coil's radius r(lambda)")
    ax[0].set(xlabel="hub angle [rad]", ylabel="force [N]", title="tension")
    rho = np.array([theory.outer_radius_after_rotation(a, r_hub, tp.h) for a in angle]) - tp.h / 2
    steady = rho * (T + tp.b * theory.energy_density(rho, tp.R, config.wall.bending, config.coiling.sense))
    if "hub_torque" in h:  # the energy balance: not measured by the hybrid
        ax[1].plot(angle, h["hub_torque"] * 1e3, ".-", label="shell (secant of the energy balance)")
    if "hub_torque_reaction" in h:
        ax[1].plot(angle, h["hub_torque_reaction"] * 1e3, "-", label=f"{model} (the root's reactions)")
    ax[1].plot(angle, steady * 1e3, "--", label="steady coiling r (T + b w(r))")
    title = "hub torque" if "hub_torque" in h else "hub torque (the hybrid's from the root's reactions)"
    ax[1].set(xlabel="hub angle [rad]", ylabel="hub torque [N mm]", title=title)
    return _save(fig, figures / "coiling_forces.png")


def coil_radius(directory: Path) -> Path | None:
    """Outer coil radius against hub angle and the radius of each turn, against the spiral."""
    h = _coiling_rows(directory)
    if h is None or len(h["hub_angle"]) == 0:
        return None
    config, summary, figures = _setup(directory)
    tp, r_hub = config.tape, config.hub.radius
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    angle = h["hub_angle"]
    wound = angle > math.pi  # before half a turn the probe sits at the lift-off point
    ax[0].plot(angle[wound], h["outer_radius"][wound] * 1e3, label="shell: outer face, half a turn back")
    ax[0].plot(
        angle,
        [theory.outer_radius_after_rotation(a, r_hub, tp.h) * 1e3 for a in angle],
        "--",
        label="r_hub + h theta / 2 pi",
    )
    ax[0].set(xlabel="hub angle [rad]", ylabel="radius [mm]", title="outer coil radius")
    radii = summary.get("coiling", {}).get("measures", {}).get("turn_radii", [])
    if radii:
        n = np.arange(len(radii))
        ax[1].plot(
            n, (np.array(radii) - r_hub) / tp.h, "o", label="shell: centre line, half a turn from the root"
        )
        ax[1].plot(n, 0.5 + n, "--", label="r_n = r_hub + h/2 + n h (physics.md Sec. 2)")
        ax[1].set(xlabel="turn n", ylabel="(r_n - r_hub) / h", title="radius of each turn")
    return _save(fig, figures / "coil_radius.png")


def coil_profiles(directory: Path) -> Path | None:
    """Curvatures and surface stresses of the stowed coil along the length and across the width."""
    path = directory / "coiled_cells.csv"
    if not path.is_file():
        return None
    config, summary, figures = _setup(directory)
    tp, r_hub, h = config.tape, config.hub.radius, config.tape.h
    data = np.genfromtxt(path, delimiter=",", names=True)
    angle = summary["coiling"]["hub_angle"]
    psi = data["psi"]
    turn = np.floor(psi / (2 * math.pi))
    rho = r_hub + h / 2 + h * turn
    coiled = (psi > 1.0) & (psi < angle - 1.0)
    centre = np.abs(data["xi2"]) <= np.min(np.abs(data["xi2"])) + 1e-12
    sel = centre & coiled
    if not sel.any():  # no coiled interior yet: nothing to draw
        return None
    # across the width: the row of cells of the coiled interior nearest the middle of the
    # middle turn (half a turn from the root step)
    target = 2 * math.pi * np.floor(angle / (4 * math.pi)) + math.pi
    station = data["xi1"][sel][np.argmin(np.abs(psi[sel] - target))]
    middle = coiled & np.isclose(data["xi1"], station, rtol=0, atol=1e-9)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.4))
    s = data["xi1"][sel] * 1e3
    sx_ref, sy_ref = np.abs(
        theory.coil_stresses(rho[sel], tp.R, config.wall.stiffness_at(h / 2), h / 2, config.coiling.sense)
    )
    ax[0].plot(s, np.abs(data["kappa_long"][sel]) * rho[sel], ".", label="|kappa_long| x turn radius")
    ax[0].plot(s, np.abs(data["kappa_trans"][sel]) * tp.R, ".", label="|kappa_trans| x R (flat: 0)")
    ax[0].plot(s, np.abs(data["sigma_x"][sel]) / sx_ref, ".", label="|sigma_x| / plate theory")
    ax[0].plot(s, np.abs(data["sigma_y"][sel]) / sy_ref, ".", label="|sigma_y| / plate theory")
    ax[0].axhline(1.0, color="k", lw=0.8)
    ax[0].set(
        xlabel="position along the tape [mm]",
        ylabel="ratio [-]",
        title="along the coiled length (centre line)",
        ylim=(-0.1, 1.4),
    )
    xi2 = data["xi2"][middle] / tp.b
    sx_ref, sy_ref = np.abs(
        theory.coil_stresses(rho[middle], tp.R, config.wall.stiffness_at(h / 2), h / 2, config.coiling.sense)
    )
    order = np.argsort(xi2)
    ax[1].plot(xi2[order], np.abs(data["sigma_x"][middle])[order] / 1e6, "o-", label="|sigma_x| shell")
    ax[1].plot(xi2[order], sx_ref[order] / 1e6, "--", label="sigma_x plate theory")
    ax[1].plot(xi2[order], np.abs(data["sigma_y"][middle])[order] / 1e6, "s-", label="|sigma_y| shell")
    ax[1].plot(xi2[order], sy_ref[order] / 1e6, ":", label="sigma_y plate theory")
    ax[1].axvspan(-0.3, 0.3, color="grey", alpha=0.1, label="inner 60 % of the width")
    ax[1].set(
        xlabel="position across the width / arc width [-]",
        ylabel="surface stress at z = h/2 [MPa]",
        title=f"across the width, {station * 1e3:.0f} mm from the root",
    )
    return _save(fig, figures / "coil_profiles.png")


def _deployment(directory: Path, needs: str | None = None):
    """The deployment's history, configuration, summary and figures directory; None without a
    deployment history (or without its column ``needs``)."""
    h = read_history(directory / "deployment_history.csv")
    if h is None or (needs is not None and needs not in h):
        return None
    return (h, *_setup(directory))


def deployment_lambda(directory: Path) -> Path | None:
    """Deployed fraction lambda(t) against Eq. 2.20 and the modified ODE (mu and plate energy)."""
    run = _deployment(directory)
    if run is None:
        return None
    from tapecoil.measures.deployment import deployment_reference

    h, config, summary, figures = run
    tp, r_hub = config.tape, config.hub.radius
    lam0 = summary["deployment"]["measures"]["lambda0"]
    t = h["time"]
    ode = deployment_reference(config, lam0)
    plate = deployment_reference(config, lam0, energy="plate")
    tt = np.linspace(0.0, max(t[-1], ode.t100), 400)
    mu = theory.coil_energy_at_R(config.wall.bending, tp.R, config.coiling.sense)
    k_hub = theory.seffen_rate(mu, r_hub, tp.R, tp.alpha, tp.rho_l, tp.L)
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    ax.plot(t, h["lambda"], lw=2, label="shell (lift-off point)")
    ax.plot(tt, theory.deployed_fraction(tt, k_hub), "--", label="Eq. 2.20, r = r_hub, lambda0 = 0")
    free = ", free hub" if config.deployment.hub == "free" else ""
    ax.plot(tt, ode(tt), ":", label=f"modified ODE (mu), r(lambda), lambda0 = {lam0:.3f}{free}")
    ax.plot(tt, plate(tt), "-.", label=f"the same ODE with the plate energy w(r){free}")
    ax.axhline(0.9, color="grey", lw=0.5)
    ax.set(xlabel="time [s]", ylabel="deployed fraction lambda", title="deployment", ylim=(0, 1.05))
    return _save(fig, figures / "deployment_lambda.png")


def deployment_energies(directory: Path) -> Path | None:
    """The energy balance of the deployment: strain, kinetic and contact energy against the
    stowed energy, and below, in per cent of it, the remainder of the balance and its parts
    (the scheme's dissipation, the residual's work, the contact updates), too small to read on
    the first scale."""
    run = _deployment(directory)
    if run is None:
        return None
    h, _, summary, figures = run
    stowed = summary["deployment"]["measures"]["energy"]["stowed"]
    t = h["time"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.6), sharex=True, height_ratios=(3, 2))
    for key, label in (
        ("strain_energy", "strain"),
        ("kinetic_energy", "kinetic (tape and hub)"),
        ("contact_energy", "contact"),
    ):
        top.plot(t, h[key], label=label)
    total = h["strain_energy"] + h["kinetic_energy"] + h["contact_energy"] + h["dissipated_energy"]
    top.plot(t, total - h["external_work"], "k--", label="sum + remainder - work of the release")
    top.axhline(stowed, color="grey", lw=0.5)
    top.set(ylabel="energy [J]", title="energy balance")
    for key, label in (
        ("dissipated_energy", "remainder (stowed + work - strain - contact - kinetic)"),
        ("scheme_dissipation", "the scheme's dissipation"),
        ("residual_work", "the converged residual's work"),
        ("contact_update_energy", "contact updates between steps"),
    ):
        if key in h:
            bottom.plot(t, 100 * h[key] / stowed, label=label)
    bottom.set(xlabel="time [s]", ylabel="per cent of the stowed energy")
    return _save(fig, figures / "deployment_energies.png")


def deployment_root_loads(directory: Path) -> Path | None:
    """The force and torque the tape exerts on the hub through its root, against time."""
    run = _deployment(directory, needs="root_torque")
    if run is None:
        return None
    h, _, _, figures = run
    t = h["time"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.0), sharex=True)
    for axis in ("x", "y", "z"):
        top.plot(t, h[f"root_force_{axis}"], label=f"F_{axis}")
    top.plot(t, np.sqrt(sum(h[f"root_force_{a}"] ** 2 for a in "xyz")), "k", lw=0.8, label="|F|")
    top.set(ylabel="force on the hub [N]", title="root loads on the hub")
    bottom.plot(t, 1e3 * h["root_torque"], label="torque about the hub axis")
    bottom.set(xlabel="time [s]", ylabel="torque [N mm]")
    return _save(fig, figures / "deployment_root_loads.png")


def deployment_coil(directory: Path) -> Path | None:
    """How loose the coil is through the deployment: its opening behind the lift-off, in
    thicknesses, and the turns still wound beyond the lift-off, against time."""
    run = _deployment(directory, needs="loose_turns")
    if run is None:
        return None
    h, config, _, figures = run
    t = h["time"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 5.4), sharex=True)
    top.plot(t, h["coil_opening"] / config.tape.h)
    top.set(ylabel="opening behind the lift-off [h]", title="how loose the coil is")
    bottom.plot(t, h["loose_turns"])
    bottom.set(xlabel="time [s]", ylabel="loose turns beyond the lift-off")
    return _save(fig, figures / "deployment_coil.png")


def free_hub_figure(h: dict[str, np.ndarray], config, lam0: float, path: Path, model: str) -> Path:
    """A free hub's turn against lambda, simulated (history ``h``, by the tape's ``model``: its
    :func:`model_name`) and by the free-hub model from ``lam0``, and its rate against time."""
    from tapecoil.measures.deployment import deployment_reference

    reference = deployment_reference(config, lam0, energy="plate")
    lam = np.linspace(lam0, 1.0, 200)
    fig, (left, right) = plt.subplots(1, 2, figsize=(10.0, 4.2))
    left.plot(h["lambda"], h["hub_angle"] - h["hub_angle"][0], lw=2, label=model)
    left.plot(lam, reference.hub_turn(lam), ":", label="free-hub model (angular momentum 0)")
    left.set(xlabel="deployed fraction lambda", ylabel="hub turn since release [rad]", title="free hub")
    right.plot(h["time"], h["hub_rate"])
    right.set(xlabel="time [s]", ylabel="hub rate [rad/s]", title="hub rate (coiling sense)")
    return _save(fig, path)


def deployment_hub(directory: Path) -> Path | None:
    """A free hub's turn against lambda and its rate (:func:`free_hub_figure`)."""
    run = _deployment(directory, needs="hub_rate")
    if run is None or not np.any(run[0]["hub_rate"]):
        return None
    h, config, summary, figures = run
    lam0 = summary["deployment"]["measures"]["lambda0"]
    model = model_name(summary["deployment"]["run"])
    return free_hub_figure(h, config, lam0, figures / "deployment_hub.png", model)


def payout_forces(directory: Path) -> Path | None:
    """A driven hub's payout against lambda: T - N on the outer turn against Eq. 4.5 and Eq. 2.6 at
    its measured radius, T - N at the root against Eq. 2.6 at the first turn, the hub torque from
    the reactions against steady coiling."""
    h = read_history(directory / "payout_history.csv")
    if h is None or len(h["hub_angle"]) == 0:
        return None
    config, summary, figures = _setup(directory)
    tp = config.tape
    model = model_name(summary.get("payout", {}).get("run", {}))
    lam = h["lambda"]
    order = np.argsort(lam)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    ax[0].plot(lam, h["coiling_tension_outer"], ".", ms=3, label=f"T - N on the outer turn ({model})")
    ax[0].plot(lam[order], h["eq_4_5"][order], "k-", lw=1.2, label="Eq. 4.5, mid-surface radius rho(lambda)")
    ax[0].plot(lam, h["eq_2_6_outer"], "k:", lw=1, label="Eq. 2.6 at the outer turn's measured radius")
    if "eq_2_6_edges_outer" in h and np.isfinite(h["eq_2_6_edges_outer"]).any():
        ax[0].plot(
            lam,
            h["eq_2_6_edges_outer"],
            "k-.",
            lw=1,
            label="the same with the free edges' share (edge layer)",
        )
    ax[0].plot(lam, h["coiling_tension"], ".", ms=3, label=f"T - N at the root ({model})")
    rho = config.hub.radius + tp.h / 2
    root = theory.coiling_tension_bending(config.wall.bending, tp.alpha, tp.R, rho)
    ax[0].axhline(root, color="k", ls="--", lw=1, label=f"Eq. 2.6 at the first turn: {root:.3f} N")
    ax[0].set(xlabel="deployed fraction lambda", ylabel="force [N]", title="coiling tension, driven hub")
    ax[1].plot(lam, h["hub_torque_reaction"] * 1e3, ".", ms=3, label=f"{model} (the root's reactions)")
    ax[1].plot(
        lam[order], h["steady_torque"][order] * 1e3, "k--", lw=1, label="steady coiling rho (T + b w(rho))"
    )
    ax[1].set(xlabel="deployed fraction lambda", ylabel="hub torque [N mm]", title="hub torque")
    return _save(fig, figures / "payout_forces.png")


FIGURES = (
    coiling_energies,
    coiling_forces,
    coil_radius,
    coil_profiles,
    deployment_lambda,
    deployment_energies,
    deployment_root_loads,
    deployment_coil,
    deployment_hub,
    payout_forces,
)


def all_figures(directory: str | Path) -> list[Path]:
    """Every figure the directory has data for."""
    directory = Path(directory)
    return [p for p in (f(directory) for f in FIGURES) if p is not None]


def draw_regime_laws(ax, config, ratio_range: tuple[float, float]) -> None:
    """The coiling-tension laws against r_c / R at the mid-surface radius r_c + h/2 (physics
    brief Sec. 5 and 10): Eq. 2.6 where it is positive, the loss-of-uniqueness band
    1 < r_c/R < 3.424 shaded, and Eq. 2.9."""
    tp, bending = config.tape, config.wall.bending
    lo, hi = ratio_range
    grid = np.linspace(lo, hi, 300)
    bend = np.array(
        [theory.coiling_tension_bending(bending, tp.alpha, tp.R, x * tp.R + tp.h / 2) for x in grid]
    )
    keep = bend > 0
    ax.plot(grid[keep], bend[keep], "--", label="Eq. 2.6 (bending-dominated), mid-surface radius r_c + h/2")
    ax.plot(
        grid,
        [
            theory.coiling_tension_tension_dominated(bending, tp.alpha, tp.R, x * tp.R + tp.h / 2)
            for x in grid
        ],
        ":",
        label="Eq. 2.9 (tension-dominated)",
    )
    ax.axvspan(max(lo, 1.0), min(hi, 3.424), color="0.9", zorder=0, label="loss of uniqueness (T ~ 0)")


def force_extension(history: list[dict], required: float | None, conform_angle: float, path: Path) -> Path:
    """The wrapping study's force against the end's displacement, with the conforming wrap."""
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7.0, 6.0), sharex=True)
    for phase in ("release", "pull"):
        rows = [r for r in history if r["phase"] == phase]
        if not rows:
            continue
        d = [1e3 * r["end_displacement"] for r in rows]
        ax.plot(d, [r["force"] for r in rows], marker=".", label=phase)
        ax2.plot(d, [r["conforming_wrap_deg"] for r in rows], marker=".", label=phase)
        folds = [r["folds"] for r in rows]
        ax2.scatter(d, [r["conforming_wrap_deg"] for r in rows], c=folds, s=12, cmap="viridis", zorder=3)
    if required is not None:
        ax.axhline(required, color="k", lw=0.8, label=f"required tension {required:.3g} N")
    ax2.axhline(conform_angle, color="k", lw=0.8)
    ax.set(ylabel="force on the end [N]", title="wrapping: force against extension")
    ax2.set(xlabel="end displacement along the pull [mm]", ylabel="conforming wrap [deg] (colour: folds)")
    return _save(fig, path)
