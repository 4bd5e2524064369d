"""The coiling tension T - N read at the root and across sections of the coil, on a short tape.

A piece of the benchmark tape (default 0.12 m, default mesh along it, --across elements across
its width) is flattened and coiled to --angle rad in steps of --step rad, one turn at most, so
no second turn and no obstacle but the hub enter. After every step past --from rad the axial
force N is read at the root (the attachment's reaction) and across the sections 1.0 and 1.5 rad
of winding from the root (measures.section_forces); the means over the steps of T - N are
printed against Eq. 2.6 at the first turn's mid-surface radius.

    tools/env.sh run env PYTHONPATH=solver python3 tools/coil_tension_profile.py --across 18
"""

import argparse
import dataclasses

import numpy as np
from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import CoilingConfig, Config, ContactConfig, TapeConfig
from tapecoil.measures.section_forces import SectionForces
from tapecoil.phases.coiling import CoilingProblem
from tapecoil.phases.coiling_run import CoilingRun

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--length", type=float, default=0.12, help="tape length [m]")
parser.add_argument("--across", type=int, default=0, help="elements across the width (0: the preset's)")
parser.add_argument("--angle", type=float, default=3.4, help="final hub angle [rad]")
parser.add_argument("--from", dest="start", type=float, default=2.6, help="first hub angle measured [rad]")
parser.add_argument("--step", type=float, default=0.05, help="largest hub-angle step [rad]")
parser.add_argument("--smoothing", type=float, default=0.0, help="contact.smoothing [-]")
parser.add_argument(
    "--thickness",
    type=float,
    default=0.0,
    help="tape thickness [m] (0: the benchmark's); the pull is scaled with D, as h^3",
)
args = parser.parse_args()

base = Config()
h = args.thickness or base.tape.h
pull = base.coiling.tension * (h / base.tape.h) ** 3
config = dataclasses.replace(
    base,
    tape=dataclasses.replace(TapeConfig(), L=args.length, h=h),
    coiling=dataclasses.replace(CoilingConfig(), hub_angle=args.angle, max_step=args.step, tension=pull),
    contact=dataclasses.replace(ContactConfig(), smoothing=args.smoothing),
    mesh=dataclasses.replace(base.mesh, preset="default", elements_across=args.across),
)
comm = MPI.COMM_WORLD
model = CoilingProblem(config, comm)
run = CoilingRun(model)
sections = SectionForces(model.model, model.tape.contact.nodes, comm)
stations = (1.0, 1.5)
readings: list[list[float]] = []


def measure(row: dict) -> None:
    if row["hub_angle"] < args.start - 1e-9:
        return
    cut = sections()
    line = model.tape.centre_line()
    psi = np.interp(cut["xi1"], line["xi1"], line["psi"])
    coil = [row["tension"] - cut["axial_force"][np.argmin(np.abs(psi - s))] for s in stations]
    readings.append([row["hub_angle"], row["coiling_tension"], *coil])


run.on_step = measure
run.flatten()
run.coil(args.angle)
tp = config.tape
law = theory.coiling_tension_bending(config.wall.bending, tp.alpha, tp.R, config.hub.radius + tp.h / 2)
values = np.array(readings)
res = model.strip.resolution
if comm.rank == 0:
    print(f"h = {h:g} m, pull {pull:.4g} N; mesh {res.along} x {res.across}, {len(values)} steps")
    print(f"Eq. 2.6 at the first turn's mid-surface radius: {law:.4f} N")
    names = ["root (reaction)"] + [f"section {s:g} rad from the root" for s in stations]
    for k, name in enumerate(names, start=1):
        mean, spread = values[:, k].mean(), np.ptp(values[:, k])
        print(f"T - N at the {name:<30} mean {mean:.4f} N ({mean / law - 1:+.1%}), spread {spread:.4f} N")
