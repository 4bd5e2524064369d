# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # Your own shell problem: Sze's pinched semicylinder
#
# `ShellProblem` states a shell problem the way a benchmark is stated: a surface, a material,
# supports on named edges, loads per unit of one load parameter, and the load steps. This demo
# states one of the benchmarks of Sze, Liu and Lo (2004), *Popular benchmark problems for
# geometric nonlinear analysis of shells*, from nothing but its data, with a surface given by
# its map.
#
# A semicylinder of radius $R = 1.016$, length $L = 3.048$ and thickness $h = 0.03$
# ($E = 2.0685 \times 10^7$, $\nu = 0.3$) is clamped at one curved end. Its straight edges lie
# on the plane through the axis, a plane of symmetry of the whole cylinder: they stay in it.
# A point force $P$ at the crown of the free end pushes towards the axis. Sze et al. give the
# deflection under the load at $P = 2000$:
#
# $$ W(P = 2000) = 1.715. $$
#
# Run: `make run CMD="python3 demos/sze_semicylinder.py [ACROSS ALONG]"` (elements around the
# half circle and along the length, default 20 20), or under `mpirun -n 2`. With
# `TAPECOIL_DEMO_SMOKE=1` (how the tests run it) the mesh is 8 x 8, too coarse to meet the
# reference, and the steps are the same.

# %%
import json
import math
import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from mpi4py import MPI

from tapecoil.geometry.meshes import MeshResolution
from tapecoil.geometry.surfaces import MappedSurface
from tapecoil.models.problem import ShellProblem
from tapecoil.models.shell import ShellMaterial

smoke = os.environ.get("TAPECOIL_DEMO_SMOKE") == "1"
across, along = (int(n) for n in sys.argv[1:3]) if len(sys.argv) > 2 else ((8, 8) if smoke else (20, 20))
out = Path("results") / ("sze_semicylinder-smoke" if smoke else "sze_semicylinder")
rank0 = MPI.COMM_WORLD.rank == 0
if rank0:
    out.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## The surface, by its map
#
# The parameters are $\xi_1 \in [0, L]$ along the axis and the polar angle
# $\xi_2 \in [-\pi/2, \pi/2]$ round it, the crown at $\xi_2 = 0$:
#
# $$ \phi_0(\xi) = \left( \xi_1,\; R \sin\xi_2,\; R (1 - \cos\xi_2) \right). $$
#
# The map is written once with the functions of `ops` (`ops.sin`, `ops.cos`, ...): the same
# function gives the points for the mesh and the UFL expression for the shell, and its
# Jacobian follows from it. `check()` compares that Jacobian with finite differences of the
# map over the closed parameter rectangle and refuses a fold or a pole.

# %%
R, L, h, E, nu, P = 1.016, 3.048, 0.03, 2.0685e7, 0.3, 2000.0
semicylinder = MappedSurface(
    lambda xi, ops: (xi[0], R * ops.sin(xi[1]), R * (1 - ops.cos(xi[1]))),
    ((0.0, L), (-math.pi / 2, math.pi / 2)),
)
semicylinder.check()

# %% [markdown]
# ## Mesh, material, supports and load
#
# `MeshResolution(across, along)`: `across` elements along $\xi_2$, `along` elements along
# $\xi_1$. The edges are named by the parameter bound they lie on: the clamped end is
# `"xi1_min"`, the straight edges `"xi2_min"` and `"xi2_max"`, which lie on the plane $z = R$
# through the axis, of normal $(0, 0, 1)$. A symmetry plane keeps the edge's displacement in
# the plane and the director in it.
#
# The force is given per unit of the load parameter: with `force=(0, 0, 1)` the load parameter
# *is* $P$ in newtons, and the steps are in newtons too. (A force on a symmetry plane would be
# the model's share of the whole's: half of it. The crown is not on one.)

# %%
problem = ShellProblem(semicylinder, MeshResolution(across=across, along=along), ShellMaterial(E, nu, h))
problem.clamp("xi1_min")
for side in ("xi2_min", "xi2_max"):
    problem.symmetry_plane(side, normal=(0.0, 0.0, 1.0))
crown = (L, 0.0)
problem.point_force(crown, force=(0.0, 0.0, 1.0))

# %% [markdown]
# ## Solve
#
# The load parameter is stepped from 0 to $P$ with adaptive steps and cut-back. `on_step`
# is called after each converged step: here it records the deflection under the load, a
# collective read (call it on every rank).

# %%
path = []


def record(step):
    path.append((step.load, problem.displacement_at(crown)[2]))


history = problem.solve(P, first_step=0.1 * P, max_step=0.2 * P, on_step=record)
W = problem.displacement_at(crown)[2]

# %% [markdown]
# ## Against Sze et al.
#
# The shell's deflection against the reference, and the load-deflection path. On the default
# 20 x 20 mesh it lies within a per cent or two of Sze's 1.715; the smoke run's 8 x 8 mesh is
# stiffer.

# %%
if rank0:
    error = abs(W - 1.715) / 1.715
    print(f"deflection under the load at P = {P:g}: {W:.4f} (Sze et al.: 1.715, error {error:.2%})")
    print(
        f"mesh {across} x {along}: {len(history)} steps, "
        f"{problem.newton_iterations} Newton iterations (every attempt), {problem.wall_time:.1f} s"
    )
    (out / "summary.json").write_text(
        json.dumps(
            {"mesh": [across, along], "P": P, "W": W, "reference": 1.715, "error": error, "path": path},
            indent=2,
        )
    )
    fig, ax = plt.subplots(figsize=(5.5, 4.0))
    loads, deflections = zip(*path, strict=True)
    ax.plot(deflections, loads, "o-", ms=3, label=f"tapecoil shell, {across} x {along}")
    ax.plot([1.715], [P], "k*", ms=10, label="Sze et al. (2004): 1.715 at P = 2000")
    ax.set(xlabel="deflection under the load W", ylabel="P", title="Pinched semicylinder")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "load_deflection.png", dpi=130)
    print(f"written: {out}/summary.json, load_deflection.png")
