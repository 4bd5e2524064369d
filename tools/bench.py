"""Benchmarks (make bench): the tape fold through the snap, or the whole coiling run.

--case fold (default): the tape-fold case to --angle (default 1 rad, past the snap) on a mesh
preset; prints DOFs, load steps, Newton iterations per step, the largest converged step and the
mean time per Newton iteration (assembly and linear solve), with the machine and the MPI size.
--case coil: the benchmark coiling run (flattening, then 36 rad) into results/bench-coil-*;
prints DOFs, steps, Newton iterations, wall time, the time per Newton iteration in assembly and
in the linear solve and the turns' real contact's share of them (contact.turns = "surface"),
the time spent writing output and its share of the run, and the validated measures.
--case deploy: the deployment from the stowed state of --case coil on the same mesh and rank
count (results/bench-coil-<mesh>-np<N>/stowed; run that first) to lambda = 1, into
results/bench-deploy-*; the same figures.
--case payout: a driven hub paying the tape out of the same stowed state to lambda = 0.9 with
the pull held, into results/bench-payout-*; the same figures and the largest error of each of
its measures over the bands of lambda.
--case hybrid-coil: the benchmark coiling (flattening, then 36 rad) by the shell-beam hybrid and
by the full shell, one after the other in this session: each one's stored energy, coiled length,
outer coil radius, outer turn's coiling tension, DOFs, steps, Newton iterations and wall time, and
the hybrid's against the full shell's. The coiling alone. Both land on the hub angles every
--tension-every rad (default 0.5) from 6 rad on, where the outer turn's tension is read and
compared angle by angle (the mean difference and its standard error); the wall times include
those steps.
--case hybrid: the benchmark run (coiling to 36 rad, then the deployment to lambda = 1) with
model.kind = "hybrid" and with the full shell, one after the other in this session, into
results/bench-hybrid-*/{hybrid,shell}: every measure of both summaries row by row, and each
phase's steps, Newton iterations and wall time with the hybrid's against the full shell's, the
peaks of the root's loads on the hub and the root torque's angular impulse to lambda = 0.9. The
hybrid coils, its coiled state settles into the full shell (the stowed state and the coil's
measures), and the hybrid deploys from its own coiled state, its window following the lift-off
down the coil.
--case coil, deploy and payout keep their figures in the results directory (bench.json);
--baseline DIR (make's BASELINE=) prints each figure beside those of DIR, the same case run by
other code (a copy of results/bench-<case>-* kept before the change), and their ratio.
Run under mpirun for parallel figures: `make bench CASE=coil MESH=default NP=2`; --config (make's
CONFIG=) runs a case with the settings of a TOML configuration instead of the defaults.
"""

import argparse
import json
import platform
import time

import numpy as np
from mpi4py import MPI

from tapecoil.config import MeshConfig, ModelConfig, load_config
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.verification.tape import tape_fold

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--mesh", default="coarse", choices=("coarse", "default", "fine"))
parser.add_argument("--angle", type=float, default=1.0, help="final end rotation [rad]")
parser.add_argument("--json", action="store_true")
parser.add_argument("--config", help="a TOML configuration (default: the benchmark's defaults)")
parser.add_argument(
    "--tension-every",
    type=float,
    default=0.5,
    help="--case hybrid-coil: the hub angles [rad] apart at which both models read the tension",
)
parser.add_argument(
    "--baseline", help="--case coil, deploy or payout: a results directory of the same case to compare with"
)
parser.add_argument(
    "--case", default="fold", choices=("fold", "coil", "deploy", "payout", "hybrid-coil", "hybrid")
)
args = parser.parse_args()
machine = f"{platform.machine()}, {platform.processor() or 'cpu'}, {MPI.COMM_WORLD.size} rank(s)"

if args.case == "hybrid-coil":
    import dataclasses

    from tapecoil.verification.hybrid_coil import coil_side_by_side, describe_paired

    config = load_config(args.config)
    both = coil_side_by_side(config, args.mesh, config.coiling.hub_angle, tension_every=args.tension_every)
    if MPI.COMM_WORLD.rank == 0:
        print(f"case: coiling, flattening + {config.coiling.hub_angle:g} rad, hybrid and full shell")
        print(f"mesh: {args.mesh}; machine: {machine}")
        print(f"{'':<28} {'hybrid':>12} {'full shell':>12} {'hybrid / full':>14}")
        for key in both["hybrid"]:
            a, b = both["hybrid"][key], both["full_shell"][key]
            ratio = a / b if (a is not None and b) else None
            cells = [f"{v:>12.6g}" if v is not None else f"{'-':>12}" for v in (a, b)]
            print(
                f"{key:<28} {cells[0]} {cells[1]} {ratio:>14.5f}"
                if ratio is not None
                else f"{key:<28} {cells[0]} {cells[1]}"
            )
        print(describe_paired(both["coiling_tension_paired"]))
        print(
            "windows (hub angle, start, end):",
            ", ".join(f"({a:.2f}, {s:.4f}, {e:.4f})" for a, s, e in both["windows"]),
        )
        if args.json:
            print(json.dumps(both, indent=2))
    raise SystemExit(0)

if args.case == "hybrid":
    import dataclasses

    from tapecoil.app.pipeline import run as run_pipeline

    config = load_config(args.config)
    config = dataclasses.replace(
        config,
        mesh=dataclasses.replace(config.mesh, preset=args.mesh),
        output=dataclasses.replace(config.output, report=False),
    )
    base = f"results/bench-hybrid-{args.mesh}-np{MPI.COMM_WORLD.size}"
    # the shell's run takes the model's defaults: the window's keys act on the hybrid alone
    cases = {
        "hybrid": dataclasses.replace(config, model=dataclasses.replace(config.model, kind="hybrid")),
        "shell": dataclasses.replace(config, model=ModelConfig(kind="shell")),
    }
    for case in cases.values():
        case.check()
    summaries = {}
    for kind, case in cases.items():
        summaries[kind] = run_pipeline(case, f"{base}/{kind}", progress=False, report=False)
    if MPI.COMM_WORLD.rank == 0:
        print("case: the benchmark run (coiling to 36 rad, deployment), model.kind hybrid and shell")
        print(f"mesh: {args.mesh}; machine: {machine}")
        print(f"{'':<44} {'hybrid':>12} {'shell':>12} {'hybrid/shell':>13}")

        def row(name, a, b):
            ratio = (
                f"{a / b:>13.6f}" if isinstance(a, float | int) and isinstance(b, float | int) and b else ""
            )
            cells = [f"{v:>12.6g}" if isinstance(v, float | int) else f"{'-':>12}" for v in (a, b)]
            print(f"{name:<44} {cells[0]} {cells[1]} {ratio}")

        total = {kind: 0.0 for kind in summaries}
        for phase in ("coiling", "deployment"):
            h, f = summaries["hybrid"].get(phase), summaries["shell"].get(phase)
            if h is None or f is None:
                print(f"{phase}: not run by both")
                continue
            for name, value in f["measures"].items():
                other = h["measures"].get(name)
                if isinstance(value, dict) and "computed" in value and isinstance(other, dict):
                    row(f"{phase}: {name}", other["computed"], value["computed"])
            for key in ("dofs", "steps", "newton_iterations", "wall_time"):
                row(f"{phase}: {key}", h["run"][key], f["run"][key])
            for key in ("root_torque_peak", "root_force_peak", "root_moment_peak", "root_force_end"):
                if h.get(key) and f.get(key):
                    row(f"{phase}: {key} [N, N m]", h[key]["value"], f[key]["value"])
            for kind, s in (("hybrid", h), ("shell", f)):
                total[kind] += s["run"]["wall_time"]
        if all("deployment" in s for s in summaries.values()):
            from pathlib import Path

            from tapecoil.post.plots import read_history
            from tapecoil.verification.hybrid_deploy import IMPULSE_FRACTION, angular_impulse, time_to

            impulse = {}
            for kind in summaries:
                history = read_history(Path(f"{base}/{kind}/deployment_history.csv"))
                end = time_to(history, IMPULSE_FRACTION)
                impulse[kind] = None if end is None else angular_impulse(history, end)
            name = f"deployment: root's angular impulse to {IMPULSE_FRACTION:g} [N m s]"
            row(name, impulse["hybrid"], impulse["shell"])
        moves = summaries["hybrid"].get("deployment", {}).get("run", {}).get("window_moves")
        row("deployment: the hybrid's window moves", moves, None)
        settling = summaries["hybrid"]["coiling"]["run"]["settling"]
        row("coiling: the hybrid's own strain energy [J]", settling["strain_energy_hybrid"], None)
        row("coiling: settling's Newton iterations", settling["newton_iterations"], None)
        row("wall time, coiling + deployment [s]", total["hybrid"], total["shell"])
        if args.json:
            print(json.dumps(summaries, indent=2))
    raise SystemExit(0)

if args.case in ("coil", "deploy", "payout"):
    import dataclasses
    from pathlib import Path

    from tapecoil.phases.coiling_run import run_coiling
    from tapecoil.phases.deployment_run import run_deployment
    from tapecoil.phases.payout import run_payout

    config = load_config(args.config)
    config = dataclasses.replace(config, mesh=dataclasses.replace(config.mesh, preset=args.mesh))
    coil_dir = Path(f"results/bench-coil-{args.mesh}-np{MPI.COMM_WORLD.size}")
    baseline = {}
    if args.baseline:  # read before the run: a wrong directory fails at once
        kept = Path(args.baseline) / "bench.json"
        if not kept.is_file():
            raise SystemExit(f"--baseline {args.baseline}: no bench.json (a results directory of make bench)")
        baseline = json.loads(kept.read_text())
    if args.case == "coil":
        summary, _ = run_coiling(config, coil_dir, progress=False)
        case = "coiling, flattening + 36 rad"
    else:
        if not (coil_dir / "stowed" / "meta.json").is_file():
            raise SystemExit(
                f"no stowed state in {coil_dir}: run `make bench CASE=coil` with the same MESH and NP"
            )
        out = f"results/bench-{args.case}-{args.mesh}-np{MPI.COMM_WORLD.size}"
        if args.case == "deploy":
            summary, _ = run_deployment(config, out, stowed=coil_dir / "stowed", progress=False)
            case = "deployment from the stowed state to lambda = 1"
        else:
            summary, _ = run_payout(config, out, stowed=coil_dir / "stowed", progress=False)
            case = f"driven-hub payout from the stowed state to lambda = {config.payout.lambda_end:g}"
    run = summary["run"]
    report = {
        "case": case,
        "mesh": f"{args.mesh} ({run['mesh']})",
        "machine": machine,
    }
    report.update({k: v for k, v in run.items() if k != "mesh"})
    if run.get("output_time") is not None and run.get("process_wall_time"):
        report["output_share"] = run["output_time"] / run["process_wall_time"]
    report["completed"] = summary["completed"]
    for name, value in summary["measures"].items():
        if isinstance(value, dict) and value.get("error") is not None:
            report[f"{name} (error)"] = value["error"]
        if isinstance(value, dict) and value.get("max_error") is not None:
            report[f"{name} (largest error)"] = value["max_error"]
    out_dir = coil_dir if args.case == "coil" else Path(out)
    if MPI.COMM_WORLD.rank == 0:
        (out_dir / "bench.json").write_text(json.dumps(report, indent=2))
        if baseline:
            print(f"{'':<36} {'this code':>12} {'baseline':>12} {'ratio':>8}   (baseline: {args.baseline})")
        for key, value in report.items():
            other = baseline.get(key)
            numbers = isinstance(value, float | int) and isinstance(other, float | int)
            if numbers and not isinstance(value, bool):
                ratio = f"{value / other:>8.3f}" if other else ""
                print(f"{key:<36} {value:>12.4g} {other:>12.4g} {ratio}")
            else:
                print(f"{key:<36} {value:.4g}" if isinstance(value, float) else f"{key:<36} {value}")
    raise SystemExit(0)

config = load_config(args.config)
res = MeshResolution.from_config(MeshConfig(preset=args.mesh), config.tape.L)
t0 = time.perf_counter()
result = tape_fold(config, res, final_angle=args.angle)
wall = time.perf_counter() - t0
info = result.info
its = np.array(info["newton_iterations"])
angles = np.array([p[0] for p in info["path"]])
summary = {
    "case": f"tape fold to {args.angle:g} rad",
    "mesh": f"{args.mesh} ({info['mesh']})",
    "ranks": MPI.COMM_WORLD.size,
    "machine": f"{platform.machine()}, {platform.processor() or 'cpu'}",
    "dofs": info["dofs"],
    "steps": info["steps"],
    "newton_iterations_per_step_mean": float(its.mean()),
    "newton_iterations_per_step_max": int(its.max()),
    "largest_converged_step_rad": float(np.max(np.diff(np.concatenate([[0.0], angles])))),
    "snap_angle": info["snap_angle"],
    "time_per_iteration_assembly_s": info["time_per_iteration"]["assembly"],
    "time_per_iteration_linear_solve_s": info["time_per_iteration"]["linear_solve"],
    "wall_time_s": wall,
}
if MPI.COMM_WORLD.rank == 0:
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        for key, value in summary.items():
            print(f"{key:<36} {value:.4g}" if isinstance(value, float) else f"{key:<36} {value}")
