# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # The analytic theory of the benchmark tape
#
# Before anything is simulated, the theory of the physics brief says what to expect for the
# benchmark tape (thesis Table 3.1): how big the coil gets, how much energy it stores, how
# hard it must be pulled to coil, and how fast it deploys. This demo prints those numbers
# and draws the two curves the simulations will be compared with. It computes no finite
# elements: the coiling and deployment simulations are separate commands.
#
# Run it with `make demo` (or `make run CMD="python3 demos/theory_report.py"`).

# %%
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from tapecoil import theory as th
from tapecoil.app.cli import main as tapecoil_cli
from tapecoil.config import load_config

config = load_config(sys.argv[1] if len(sys.argv) > 1 else None)
tape, r_hub = config.tape, config.hub.radius
bending = config.wall.bending
out = Path(config.output.directory) / "theory"
out.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## The numbers
# The same table as `tapecoil theory`.

# %%
tapecoil_cli(["theory", *sys.argv[1:2]])

# %% [markdown]
# ## Deployment: deployed fraction against time
# Seffen and Pellegrino's Eq. 2.20 assumes a constant coil radius; the thesis's Eq. 4.4 lets
# the radius shrink as the tape unrolls, and Eq. 2.24 adds the initial unspooled fraction
# lambda0 (0.04 is the thesis's 20 mm of 500 mm).


# %%
def rate(r):
    return th.seffen_rate(
        th.coil_energy_at_R(bending, tape.R, config.coiling.sense), r, tape.R, tape.alpha, tape.rho_l, tape.L
    )


def rate_growing(lam):
    return rate(th.coil_radius_during_deployment(lam, r_hub, tape.h, tape.L))


r_coil = th.outer_radius_after_rotation(config.coiling.hub_angle, r_hub, tape.h)
t = np.linspace(0.0, 0.5, 501)
fig, ax = plt.subplots(figsize=(6.4, 4.2))
for r, label in [
    (r_hub, f"Eq. 2.20, r = r_hub = {r_hub * 1e3:.2f} mm"),
    (r_coil, f"Eq. 2.20, r = {r_coil * 1e3:.2f} mm"),
]:
    ax.plot(t, th.deployed_fraction(t, rate(r)), label=label)
for lam0 in (0.0, 0.04):
    sol = th.solve_deployment_ode(rate_growing, lam0)
    ax.plot(t, sol(t), "--", label=f"Eq. 4.4 (growing radius), lambda0 = {lam0:g}: T = {sol.t100:.3f} s")
ax.axhline(0.9, color="0.6", lw=0.8)
ax.set(
    xlabel="time t [s]",
    ylabel="deployed fraction lambda [-]",
    ylim=(0, 1.05),
    title="Deployment of the benchmark tape (theory)",
)
ax.legend(fontsize=8, loc="lower right")
fig.tight_layout()
fig.savefig(out / "deployment_theory.png", dpi=130)

# %% [markdown]
# ## Coiling tension against hub size
# Bending-dominated coiling (r_c/R <= 1) needs Eq. 2.6; beyond the loss of uniqueness
# (r_c/R > 3.424) coiling is tension-dominated, Eq. 2.9.

# %%
ratio_b = np.linspace(0.4, 1.0, 100)
ratio_t = np.linspace(th.UNIQUENESS_LIMIT, 5.25, 100)
fig, ax = plt.subplots(figsize=(6.4, 4.2))
ax.plot(
    ratio_b,
    [th.coiling_tension_bending(bending, tape.alpha, tape.R, x * tape.R) for x in ratio_b],
    label="Eq. 2.6 (bending-dominated)",
)
ax.plot(
    ratio_t,
    [th.coiling_tension_tension_dominated(bending, tape.alpha, tape.R, x * tape.R) for x in ratio_t],
    label="Eq. 2.9 (tension-dominated)",
)
ax.axvspan(1.0, th.UNIQUENESS_LIMIT, color="0.92", label="loss of uniqueness")
T_bench = th.coiling_tension_bending(bending, tape.alpha, tape.R, r_hub)
ax.plot([r_hub / tape.R], [T_bench], "ko", label=f"benchmark hub: {T_bench:.3f} N")
ax.set(
    xlabel="r_c / R [-]",
    ylabel="coiling tension T [N]",
    yscale="log",
    title="Tension needed to coil (theory)",
)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out / "coiling_tension_theory.png", dpi=130)
print(f"\nplots written to {out}/ (deployment_theory.png, coiling_tension_theory.png)")
theta = config.coiling.hub_angle
wound = th.coiled_length_from_rotation(theta, r_hub, tape.h)
print(f"hub angle {theta:g} rad coils {wound:.3f} m in {theta / (2 * math.pi):.2f} turns")
