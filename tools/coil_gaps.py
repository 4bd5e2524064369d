"""How tight a deploying coil stays behind its lift-off, read from a run's surface snapshots.

For every deployment snapshot of a results directory: the centre line's nodes (xi2 = 0) in
polar coordinates about the hub's axis (:class:`tapecoil.hub.frame.HubFrame`), each node's gap
to the turn beneath it (its radius less that of the centre line one turn less wound, at the
same angle, less h), the lift-off (the last node, from the root, within LIFT_OFF_GAP h of its
turn) and, behind it, the largest gap and how far behind the lift-off it lies. A coil that
loosens behind its lift-off (the hybrid's flattened beam stops where it lifts by more than the
lift-off gap) shows here as gaps of more than LIFT_OFF_GAP h behind the lift-off.

    tools/env.sh run env PYTHONPATH=solver python3 tools/coil_gaps.py results/deploy [--every 4]
"""

import argparse
from pathlib import Path

import numpy as np

from tapecoil.config import load_config
from tapecoil.hub.frame import HubFrame
from tapecoil.measures.deployment import LIFT_OFF_GAP
from tapecoil.measures.separation import snapshot_files

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("results", type=Path, help="a deployment's results directory (snapshots/)")
parser.add_argument("--every", type=int, default=4, help="print every n-th snapshot")
args = parser.parse_args()

config = load_config(args.results / "config.toml")
h = config.tape.h
frame = HubFrame(config.hub.radius, h, config.coiling.sense)
files, cells_file = snapshot_files(args.results, "deployment")
xi = np.load(cells_file)["xi"]
line = np.flatnonzero(np.abs(xi[:, 1]) < 1e-9)
line = line[np.argsort(xi[line, 0])]
s = xi[line, 0]
centre = frame.axis_point

rows = []
for path in files:
    snapshot = np.load(path)
    p = snapshot["points"][line] - centre
    r = np.hypot(p[:, 0], p[:, 2])
    psi = np.abs(np.unwrap(np.arctan2(p[:, 0], p[:, 2])) - np.arctan2(p[0, 0], p[0, 2]))
    wound = np.maximum.accumulate(psi)  # the winding angle, made monotone past the lift-off
    inner = np.interp(psi - 2 * np.pi, wound, r, left=np.nan, right=np.nan)
    gap = (r - inner - h) / h
    on = np.flatnonzero(gap <= LIFT_OFF_GAP)
    if len(on) == 0:
        continue
    lift = s[on.max()]
    behind = np.where(s < lift, gap, np.nan)
    if np.all(np.isnan(behind)):
        continue
    worst = int(np.nanargmax(behind))
    rows.append((float(snapshot["t"]), lift, behind[worst], lift - s[worst]))

print(f"{'t [s]':>9} {'lift-off [m]':>13} {'largest gap behind it [h]':>26} {'behind by [m]':>14}")
for row in rows[:: args.every]:
    print(f"{row[0]:9.4f} {row[1]:13.3f} {row[2]:26.2f} {row[3]:14.3f}")
late = [row for row in rows if row[0] >= 0.02]
if late:
    print(f"from 20 ms on: largest gap behind the lift-off {max(row[2] for row in late):.2f} h")
