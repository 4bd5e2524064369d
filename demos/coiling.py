# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # Coiling the benchmark tape onto its hub
#
# The thesis's benchmark (physics.md Sec. 1): a BeCu tape spring, R = 15.1 mm, alpha = 135 deg,
# h = 0.1 mm, 0.5 m long, is coiled onto a hub of radius 12.7 mm by 36 rad of hub rotation
# (5.7 turns) with a 1 N pull at the free end. The thesis did it with an explicit code in
# 5 h 32 min on 28 cores; here it is a quasi-static implicit run:
#
# 1. the root edge, attached to the hub, is flattened onto it while the pull rises to 1 N;
# 2. the hub turns in adaptive load steps; the tape wraps onto the hub and then onto its own
#    turns (penalty contact with a spiral obstacle that follows each point's winding angle);
#    the free end slides along the guide line tangent to the hub.
#
# In the coil the section is flat and the longitudinal radius is the local coil radius, so
# the stored energy per unit area is the plate estimate
# $$ w(\rho) = \frac{D}{2}\left(\frac{1}{\rho^2} + \frac{1}{R^2} + \frac{2\nu}{\rho R}\right), $$
# and the coil grows by one thickness per turn: $r = r_{hub} + h\,\Theta / (2\pi)$.
#
# Run: `make run CMD="python3 demos/coiling.py [coarse|default|fine]"`, or under
# `mpirun -n 2` (the render is then skipped). ParaView: `results/coiling-<mesh>/coil.bp`,
# *Warp By Vector* with `offset`.

# %%
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import dataclasses

import matplotlib.pyplot as plt
import numpy as np
from mpi4py import MPI

from tapecoil import theory
from tapecoil.coiling import run_coiling
from tapecoil.config import load_config

preset = sys.argv[1] if len(sys.argv) > 1 else "coarse"
config = load_config()
config = dataclasses.replace(config, mesh=dataclasses.replace(config.mesh, preset=preset))
out = Path(config.output.directory) / f"coiling-{preset}"
comm = MPI.COMM_WORLD
rank0 = comm.rank == 0

# %% [markdown]
# ## The run
# Results directory: the configuration, the history (CSV), ParaView snapshots, the stowed
# checkpoint (for the deployment) and a JSON summary.

# %%
summary, model = run_coiling(config, out, comm)
m = summary["measures"]
if rank0:
    run = summary["run"]
    print(
        f"{'stowed' if summary['completed'] else 'stopped'} at {summary['hub_angle']:.3f} rad: "
        f"{run['steps']} steps, {run['newton_iterations']} Newton iterations, {run['wall_time']:.0f} s "
        f"on {run['ranks']} rank(s), {run['dofs']} dofs"
    )
    for key in (
        "stored_energy_coiled",
        "strain_energy_total",
        "curvature_longitudinal",
        "stress_x",
        "stress_y",
        "outer_radius",
        "turn_separation",
    ):
        if m.get(key):
            e = m[key]
            row = f"computed {e['computed']:.5g}  reference {e['reference']:.5g}  error {e['error']:.2%}"
            print(f"  {key:<24} {row}")
    for key in ("ploy_length_one_turn", "ploy_length"):
        if key in m:
            print(
                f"  {key}", json.dumps({k: v for k, v in m[key].items() if k not in ("quantity", "profile")})
            )

# %% [markdown]
# ## Histories against the theory
# Energy against hub angle, with the plate estimate for the length actually coiled; the
# outer coil radius against r_hub + h Theta / (2 pi); the hub torque from the energy balance.

# %%
if rank0:
    import csv

    rows = [r for r in csv.DictReader((out / "history.csv").open()) if r["phase"] == "coil"]
    angle = np.array([float(r["hub_angle"]) for r in rows])
    energy = np.array([float(r["strain_energy"]) for r in rows])
    coiled = np.array([float(r["coiled_length"]) for r in rows])
    radius = np.array([float(r["outer_radius"]) for r in rows])
    # the torque is undefined (empty) at the first step and across snaps passed by relaxation
    torque = np.array([float(r["hub_torque"]) if r["hub_torque"] else np.nan for r in rows])
    tp, r_hub = config.tape, config.hub.radius
    ref_energy = [
        theory.stored_energy(
            theory.rotation_for_coiled_length(s, r_hub, tp.h), r_hub, tp.h, tp.R, tp.alpha, tp.D, tp.nu
        )
        for s in coiled
    ]
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    ax[0].plot(angle, energy, label="shell, whole tape")
    ax[0].plot(angle, ref_energy, "--", label="plate estimate, coiled length")
    ax[0].set(xlabel="hub angle [rad]", ylabel="strain energy [J]", title="stored energy")
    # before half a turn the probe would sit at the lift-off point: not a coil radius yet
    wound = angle > np.pi
    ax[1].plot(
        angle[wound], radius[wound] * 1e3, label="shell: outer face, half a turn behind the tangent point"
    )
    ax[1].plot(
        angle,
        [theory.outer_radius_after_rotation(a, r_hub, tp.h) * 1e3 for a in angle],
        "--",
        label="r_hub + h theta / 2 pi",
    )
    ax[1].set(xlabel="hub angle [rad]", ylabel="outer radius [mm]", title="coil radius")
    ax[2].plot(angle, torque * 1e3, label="shell (secant of the energy balance)")
    # steady coiling: each radian winds r of tape, storing b w(r) per metre, against the pull T
    rho = np.array([theory.outer_radius_after_rotation(a, r_hub, tp.h) for a in angle]) - tp.h / 2
    steady = rho * (config.coiling.tension + tp.b * theory.energy_density(rho, tp.R, tp.D, tp.nu))
    ax[2].plot(angle, steady * 1e3, "--", label="r (T + b w(r))")
    ax[2].set(xlabel="hub angle [rad]", ylabel="hub torque [N mm]", title="hub torque")
    for a in ax:
        a.legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "coiling_histories.png", dpi=120)
    print("wrote", out / "coiling_histories.png")

# %% [markdown]
# ## The stowed coil
# A render of the final state with the hub (serial runs only: the render gathers nothing).

# %%
if comm.size == 1:
    from tapecoil.render import render_on_hub

    path = render_on_hub(
        model.model,
        model.axis_point,
        config,
        out / "stowed.png",
        f"stowed: hub angle {summary['hub_angle']:.1f} rad",
    )
    print("wrote", path)
