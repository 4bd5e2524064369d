"""The coiling's cost against the tape's length, hybrid beside full shell: the benchmark tape's
section and hub at length L [m] (argument), coiled until FREE [m] of it stays off the coil
(the hub angle from the theory's spiral), by the hybrid and by the full shell one after the
other (`tapecoil.verification.hybrid_coil.coil_side_by_side`), on a mesh preset (second argument,
default "default"). Prints the hub angle and, for both models, the stored energy, coiled
length, outer radius, outer turn's coiling tension, free part's height, DOFs, steps, Newton
iterations and wall time (docs/notes/hybrid.md, "Cost against the tape's length"); ``--json FILE``
also writes them there, for tools/hybrid_length_plot.py.

With ``--deploy`` the hybrid coils and then deploys to ``--lambda-end``, and the full shell
deploys from the hybrid's coil settled in it (``verification.hybrid_deploy.deploy_side_by_side``;
``--hybrid-only`` leaves the full shell out). The deployment's simulated time is scaled with the
modified ODE's (t ~ L^2): t_end is 1.5 times its time to lambda_end. Printed beside the hybrid's:
the stowed strain energy against the plate estimate (``theory.stored_energy``, which leaves out
the ploy region and the free edges' relief), the time to lambda = 0.9 against the modified ODE
with the plate energy (physics.md Sec. 6), and the coiling's and the deployment's wall times.

    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/hybrid_length_study.py 1.0
    tools/env.sh run mpirun -n 2 env PYTHONPATH=solver python3 tools/hybrid_length_study.py 2.0 \
        --deploy --lambda-end 0.9 --hybrid-only --beam-contact width --json deploy_L2.0.json
"""

import argparse
import dataclasses
import json

import numpy as np
from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import Config
from tapecoil.measures.deployment import deployment_reference
from tapecoil.verification.hybrid_coil import coil_side_by_side, describe_paired
from tapecoil.verification.hybrid_deploy import deploy_side_by_side, time_to

FREE = 0.031  # [m] the benchmark's 0.5 m at 36 rad leaves 31 mm off the coil

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("length", type=float, help="tape length L [m]")
parser.add_argument("mesh", nargs="?", default="default", choices=("coarse", "default", "fine"))
parser.add_argument("--json", help="write the results to this file as well")
parser.add_argument(
    "--deploy", action="store_true", help="coil with the hybrid, then deploy with both models"
)
parser.add_argument(
    "--lambda-end", type=float, default=1.0, help="with --deploy: the deployed fraction to stop at"
)
parser.add_argument(
    "--hybrid-only", action="store_true", help="with --deploy: leave the full shell's deployment out"
)
parser.add_argument(
    "--beam-contact",
    choices=("line", "width"),
    help="model.beam_contact: the flattened beam on the turns by its line or across its width "
    "(default the configuration's, width)",
)
parser.add_argument(
    "--max-dt",
    type=float,
    help="with --deploy: deployment.max_dt [s], the steps' bound (default the configuration's, 1 ms)",
)
parser.add_argument(
    "--rho-inf",
    type=float,
    help="with --deploy: deployment.rho_inf, generalized-alpha's spectral radius (default the "
    "configuration's, 0.5)",
)
parser.add_argument(
    "--deploy-rtol",
    type=float,
    help="with --deploy: Newton's relative tolerance in the deployment alone (deployment.petsc_options "
    "snes_rtol; default solver.rtol, 1e-8)",
)
parser.add_argument(
    "--tension-every",
    type=float,
    help="both models land on the hub angles this many radians apart from 6 rad on and compare the "
    "outer turn's tension there, angle by angle (the wall times then include those steps)",
)
args = parser.parse_args()
if not args.length > 2 * FREE:
    raise SystemExit(f"the tape must be longer than {2 * FREE} m, got {args.length}")

config = Config()
angle = theory.rotation_for_coiled_length(args.length - FREE, config.hub.radius, config.tape.h)
config = dataclasses.replace(
    config,
    tape=dataclasses.replace(config.tape, L=args.length),
    coiling=dataclasses.replace(config.coiling, hub_angle=angle),
)


def with_beam_contact(config):
    """``config`` with --beam-contact's model.beam_contact, if given."""
    if args.beam_contact is None:
        return config
    return dataclasses.replace(
        config, model=dataclasses.replace(config.model, beam_contact=args.beam_contact)
    )


def deploy(config, mesh: str, angle: float, lambda_end: float, full_shell: bool) -> None:
    """Coil with the hybrid and deploy with it (and the full shell); print, and write --json."""
    lam0 = 1.0 - theory.coiled_length_from_rotation(angle, config.hub.radius, config.tape.h) / config.tape.L
    expected = deployment_reference(config, lam0, energy="plate")
    t_end = 1.5 * float(np.interp(lambda_end, expected.lam, expected.t))
    config = dataclasses.replace(
        config, deployment=dataclasses.replace(config.deployment, t_end=t_end, lambda_end=lambda_end)
    )
    settings = {
        "max_dt": args.max_dt,
        "rho_inf": args.rho_inf,
        "petsc_options": None if args.deploy_rtol is None else {"snes_rtol": args.deploy_rtol},
    }
    settings = {key: value for key, value in settings.items() if value is not None}
    config = dataclasses.replace(config, deployment=dataclasses.replace(config.deployment, **settings))
    config.check()
    # the hybrid's own setting, taken after the check (which refuses it on the full shell's
    # model.kind, the configuration's here)
    config = with_beam_contact(config)
    both = deploy_side_by_side(config, mesh, angle, full_shell=full_shell)
    tp = config.tape
    plate = theory.stored_energy(
        angle, config.hub.radius, tp.h, tp.R, tp.alpha, config.wall.bending, config.coiling.sense
    )
    sides = ["hybrid", "full_shell"] if full_shell else ["hybrid"]
    rows = {}
    for side in sides:
        run = both[side]
        rows[side] = {
            "stowed_energy": float(run["strain_energy"][0]),
            "time_to_0.9": time_to(run, 0.9),
            f"time_to_{lambda_end:g}": time_to(run, lambda_end),
            "completed": bool(run["completed"]),
            "dofs": run["dofs"],
            "steps": run["steps"],
            "newton_iterations": run["newton_iterations"],
            "wall_time": run["wall_time"],
        }
    # the modified ODE from the hybrid's own deployed fraction at release
    plate_ode = deployment_reference(config, float(both["hybrid"]["lambda"][0]), energy="plate")
    rows["hybrid"]["stopped"] = both["hybrid"]["stopped"]
    rows["hybrid"]["coiling_wall_time"] = both["hybrid"]["coiling_wall_time"]
    rows["hybrid"]["coiling_steps"] = both["hybrid"]["coiling_steps"]
    rows["hybrid"]["window_moves"] = len(both["moves"]) - 1
    reference = {"plate_stored_energy": plate, "plate_ode_time_to_0.9": plate_ode.t90, "t_end": t_end}
    if MPI.COMM_WORLD.rank != 0:
        return
    ranks = MPI.COMM_WORLD.size
    print(f"L = {tp.L:g} m, hub angle {angle:.4g} rad, lambda0 {lam0:.4f}, mesh {mesh}, {ranks} rank(s)")
    for side, row in rows.items():
        print(side)
        for key, value in row.items():
            print(f"  {key:<24} {value}")
    hybrid = rows["hybrid"]
    print(f"stowed energy / plate estimate      {hybrid['stowed_energy'] / plate:.5f} ({plate:.5g} J)")
    if hybrid["time_to_0.9"] is not None:
        ratio = hybrid["time_to_0.9"] / plate_ode.t90
        print(f"time to 0.9 / modified ODE (plate)  {ratio:.5f} ({plate_ode.t90:.5g} s)")
    print(f"coiling + deployment wall [s]       {hybrid['coiling_wall_time'] + hybrid['wall_time']:.1f}")
    if args.json:
        record = {"length": tp.L, "hub_angle": angle, "mesh": mesh, "ranks": ranks}
        record["beam_contact"] = config.model.beam_contact
        record["max_dt"] = config.deployment.max_dt
        record["rho_inf"] = config.deployment.rho_inf
        record["deployment_petsc_options"] = config.deployment.petsc_options
        with open(args.json, "w") as f:
            json.dump({**record, "lambda_end": lambda_end, **reference, **rows}, f, indent=1)


if args.deploy:
    deploy(config, args.mesh, angle, args.lambda_end, not args.hybrid_only)
    raise SystemExit(0)
config = with_beam_contact(config)
both = coil_side_by_side(config, args.mesh, angle, tension_every=args.tension_every)
if MPI.COMM_WORLD.rank == 0:
    print(
        f"L = {args.length:g} m, hub angle {angle:.4g} rad, mesh {args.mesh}, {MPI.COMM_WORLD.size} rank(s)"
    )
    print(f"{'':<26} {'hybrid':>14} {'full shell':>14} {'hybrid / full':>14}")
    for key, value in both["hybrid"].items():
        full = both["full_shell"][key]
        ratio = f"{value / full:>14.5f}" if value is not None and full else ""
        cells = [f"{v:>14.6g}" if v is not None else f"{'-':>14}" for v in (value, full)]
        print(f"{key:<26} {cells[0]} {cells[1]} {ratio}")
    print(f"window moves: {len(both['windows']) - 1}")
    if both["coiling_tension_paired"] is not None:
        print(describe_paired(both["coiling_tension_paired"]))
    if args.json:
        record = {"length": args.length, "hub_angle": angle, "mesh": args.mesh, "ranks": MPI.COMM_WORLD.size}
        with open(args.json, "w") as f:
            json.dump({**record, **both}, f, indent=1)
