# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # Deploying the stowed tape
#
# The second half of the thesis's benchmark (physics.md Sec. 6): the coiled tape of
# `demos/coiling.py` is released. The pull and the guide at the free end let go (over
# 2 ms), the hub stays fixed, the root stays attached, and the stored strain energy drives the
# free part round the hub, peeling the tape off the coil. The motion is integrated implicitly
# (generalized-alpha, adaptive steps) with the shell's translational and rotary inertia.
#
# Seffen and Pellegrino's model: a straight deployed part tangent to the coil, energy
# mu b released per unit length unspooled, gives for the deployed fraction lambda
# $$ \dot\lambda = k(\lambda) \sqrt{\frac{\lambda - \lambda_0}{\lambda^3}}, \qquad
#    k = \sqrt{\frac{6 \mu r^2 R \alpha}{\rho_l L^4}}, $$
# with r = r_hub (Eq. 2.20 for lambda0 = 0) or the coil radius r(lambda) of Eq. 4.4 (the
# thesis's modified equation); lambda0 is the fraction already off the coil at release.
#
# Run after the coiling demo: `make run CMD="python3 demos/deployment.py [coarse|default]"`
# (or `make demo`, which runs both). ParaView: `results/coiling-<mesh>/deployment.bp`.

# %%
import dataclasses
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import load_config
from tapecoil.deployment import deployment_reference, run_deployment

preset = sys.argv[1] if len(sys.argv) > 1 else "coarse"
config = load_config()
config = dataclasses.replace(config, mesh=dataclasses.replace(config.mesh, preset=preset))
out = Path(config.output.directory) / f"coiling-{preset}"
comm = MPI.COMM_WORLD
rank0 = comm.rank == 0
if not (out / "stowed" / "meta.json").is_file():
    raise SystemExit(f"no stowed state in {out}: run demos/coiling.py {preset} first")

# %% [markdown]
# ## The run
# From the stowed checkpoint to lambda = 1 (the tape unwound down to the root).

# %%
summary, model = run_deployment(config, out, comm, stowed=out / "stowed")
m = summary["measures"]
if rank0:
    run = summary["run"]
    print(
        f"{'deployed' if summary['completed'] else 'stopped'} at t = {summary['time']:.4f} s, "
        f"lambda = {summary['lambda']:.3f}: {run['steps']} steps, {run['newton_iterations']} Newton "
        f"iterations, {run['wall_time']:.0f} s on {run['ranks']} rank(s), {run['dofs']} dofs"
    )
    for key in ("time_to_0.9", "time_to_end"):
        e = m[key]
        if e["computed"] is not None:
            print(
                f"  {key:<12} computed {e['computed']:.4f} s  reference {e['reference']:.4f} s  "
                f"error {e['error']:.2%}"
            )
    print("  energy", {k: round(v, 5) for k, v in m["energy"].items()})

# %% [markdown]
# ## lambda(t) and the energies
# The measured deployed fraction against Eq. 2.20 (r = r_hub, lambda0 = 0) and the modified ODE
# started from the simulation's own lambda0; the strain, kinetic and contact energies and the
# energy removed by the time integration.

# %%
if rank0:
    import csv

    rows = list(csv.DictReader((out / "deployment_history.csv").open()))
    col = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    t = col["time"]
    tp, r_hub = config.tape, config.hub.radius
    k_hub = theory.seffen_rate(tp.mu, r_hub, tp.R, tp.alpha, tp.rho_l, tp.L)
    ode = deployment_reference(config, m["lambda0"])
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    ax[0].plot(t, col["lambda"], label="shell (lift-off point)")
    tt = np.linspace(0.0, max(t[-1], ode.t100), 400)
    ax[0].plot(tt, theory.deployed_fraction(tt, k_hub), "--", label="Eq. 2.20, r = r_hub, lambda0 = 0")
    ax[0].plot(tt, ode(tt), ":", label=f"modified ODE, r(lambda), lambda0 = {m['lambda0']:.3f}")
    ax[0].axhline(0.9, color="grey", lw=0.5)
    ax[0].set(xlabel="time [s]", ylabel="deployed fraction lambda", title="deployment", ylim=(0, 1.05))
    stowed = m["energy"]["stowed"]
    ax[1].plot(t, col["strain_energy"], label="strain")
    ax[1].plot(t, col["kinetic_energy"], label="kinetic")
    ax[1].plot(t, col["contact_energy"], label="contact")
    ax[1].plot(t, col["dissipated_energy"], label="numerically dissipated")
    total = col["strain_energy"] + col["kinetic_energy"] + col["contact_energy"] + col["dissipated_energy"]
    ax[1].plot(t, total - col["external_work"], "k--", label="sum - work of the release")
    ax[1].axhline(stowed, color="grey", lw=0.5)
    ax[1].set(xlabel="time [s]", ylabel="energy [J]", title="energy balance")
    for a in ax:
        a.legend(fontsize=8)
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "deployment_histories.png", dpi=120)
    print("wrote", out / "deployment_histories.png")

# %% [markdown]
# ## The deployed tape
# A render of the last state with the hub (serial runs only).

# %%
if comm.size == 1:
    from tapecoil.render import render_on_hub

    path = render_on_hub(
        model.model,
        model.coiling.axis_point,
        config,
        out / "deployed.png",
        f"deployment: t = {summary['time']:.3f} s, lambda = {summary['lambda']:.2f}",
    )
    print("wrote", path)
