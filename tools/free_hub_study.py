"""The benchmark deployment with a free hub against the free-hub model (docs/notes/deployment.md).

    tools/env.sh run mpirun -n 2 python3 tools/free_hub_study.py --inertia 10 --max-dt 2.5e-4

deploys the coarse benchmark from the coiling validation's stowed state
(results/validate-coil-coarse, coiled first if it is not there) with the hub free to turn, of
rotary inertia ``--inertia`` times the stowed tape's own (theory.stowed_rotary_inertia), into
results/free-hub-J<inertia>, and prints the times and hub turns at
lambda = 0.2 ... 0.9 against the model with the plate energy, how loose the coil came (its
largest opening behind the lift-off and its loose turns beyond it), and the angular momentum kept;
the hub's turn against lambda is drawn into free_hub.png there.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np
from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import load_config
from tapecoil.measures.deployment import at_crossing, deployment_reference
from tapecoil.phases.coiling_run import run_coiling
from tapecoil.phases.deployment_run import run_deployment
from tapecoil.post.plots import free_hub_figure, model_name, read_history


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--inertia", type=float, default=10.0, help="J over the stowed tape's own")
    parser.add_argument("--max-dt", type=float, default=2.5e-4, help="largest time step [s]")
    parser.add_argument("--lambda-end", type=float, default=0.95)
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    config = load_config()
    config = dataclasses.replace(config, mesh=dataclasses.replace(config.mesh, preset="coarse"))
    coil_dir = Path("results/validate-coil-coarse")
    meta = coil_dir / "stowed" / "meta.json"
    ready = meta.is_file() and json.loads(meta.read_text()).get("completed")
    if not comm.allreduce(bool(ready), op=MPI.LAND):
        run_coiling(config, coil_dir, comm, progress=False)
    tp, r_hub = config.tape, config.hub.radius
    inertia = args.inertia * theory.stowed_rotary_inertia(r_hub, tp.h, tp.L, tp.rho_l)
    config = dataclasses.replace(
        config,
        hub=dataclasses.replace(config.hub, inertia=inertia),
        deployment=dataclasses.replace(
            config.deployment, hub="free", max_dt=args.max_dt, lambda_end=args.lambda_end
        ),
        contact=dataclasses.replace(config.contact, stop_penetration=3.0),
        output=dataclasses.replace(config.output, report=False, vtx_every=20),
    )
    out = Path(f"results/free-hub-J{args.inertia:g}")
    summary, model = run_deployment(config, out, comm, stowed=coil_dir / "stowed", progress=False)
    if comm.rank != 0:
        return
    import csv

    with (out / "deployment_history.csv").open() as f:
        history = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    reference = deployment_reference(config, history[0]["lambda"], energy="plate")
    run = summary["run"]
    print(
        f"J = {inertia:.4g} kg m^2: {run['steps']} steps, {run['newton_iterations']} Newton iterations, "
        f"{model.coupling.iterations} hub iterations, {run['wall_time']:.0f} s on {run['ranks']} ranks"
    )
    for lam in (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9):
        t, turn = at_crossing(history, lam), at_crossing(history, lam, "hub_angle")
        if t is None:
            print(f"lambda {lam}: not reached")
            continue
        turn -= history[0]["hub_angle"]
        t_ref, turn_ref = reference.time_to(lam), reference.hub_turn(lam)
        print(
            f"lambda {lam}: t {1e3 * t:.1f} / {1e3 * t_ref:.1f} ms ({t / t_ref - 1:+.1%}), "
            f"turn {turn:.3f} / {turn_ref:.3f} rad ({turn / turn_ref - 1:+.1%})"
        )
    free_hub_figure(
        read_history(out / "deployment_history.csv"),
        config,
        history[0]["lambda"],
        out / "free_hub.png",
        model_name(run),
    )
    looseness = summary["measures"]["coil_looseness"]
    print(
        f"the coil: opening behind the lift-off at most {looseness['largest_opening_h']:.2f} h "
        f"(t {1e3 * looseness['opening_time']:.1f} ms, lambda {looseness['opening_lambda']:.3f}); "
        f"at most {looseness['most_loose_turns']:.2f} loose turns beyond the lift-off "
        f"(t {1e3 * looseness['loose_turns_time']:.1f} ms, lambda {looseness['loose_turns_lambda']:.3f})"
    )
    released = [r for r in history if r["time"] > 1.5 * config.deployment.release_time]
    H = np.array([r["angular_momentum"] for r in released])
    spin = max(abs(inertia * r["hub_rate"]) for r in history)
    print(
        f"angular momentum after the release: {H[0]:.4g}, kept to {np.abs(H - H[0]).max() / abs(H[0]):.1%} "
        f"({np.abs(H - H[0]).max() / spin:.2%} of the hub's largest J zeta')"
    )


if __name__ == "__main__":
    main()
