"""The commands that compute no finite elements: ``theory`` (the analytic predictions) and ``config``."""

from __future__ import annotations

import argparse
import json
import math

from tapecoil import __version__
from tapecoil.app.commands.common import echo
from tapecoil.config import load_config, to_toml

# Display units for the table: (SI unit, key) -> (factor, shown unit)
_DISPLAY = {"m": (1e3, "mm"), "Pa": (1e-6, "MPa"), "N m": (1e3, "N mm"), "m^4": (1e12, "mm^4")}


def _display(value: float, unit: str) -> tuple[str, str]:
    factor, shown = _DISPLAY.get(unit, (1.0, unit))
    v = value * factor
    text = f"{v:.4g}" if abs(v) < 1e5 else f"{v:.4e}"
    return text, shown


def cmd_theory(args: argparse.Namespace) -> int:
    from tapecoil.theory import predictions

    config = load_config(args.config)
    preds = predictions(config)
    if args.json:
        payload = {
            "config": args.config or "defaults (benchmark tape)",
            "predictions": {
                p.key: {"label": p.label, "value": p.value, "unit": p.unit, "source": p.source} for p in preds
            },
        }
        echo(json.dumps(payload, indent=2))
        return 0
    tp, lam = config.tape, config.laminate
    echo(f"tapecoil {__version__}: analytic predictions ({args.config or 'benchmark tape, defaults'})")
    if lam.kind == "isotropic":
        wall = f"E = {tp.E / 1e9:g} GPa, nu = {tp.nu:g}"
    else:
        d = config.wall.bending
        layup = "/".join(f"{a:g}" for a in lam.angles) if lam.kind == "plies" else "A, B, D given"
        wall = f"laminate [{layup}], D11 = {d.D11:.4g} N m, D22 = {d.D22:.4g} N m, D12 = {d.D12:.4g} N m"
    echo(
        f"tape R = {tp.R * 1e3:g} mm, alpha = {math.degrees(tp.alpha):.4g} deg, h = {tp.h * 1e3:g} mm, "
        f"L = {tp.L:g} m, {wall}, rho_l = {tp.rho_l:g} kg/m; "
        f"hub r = {config.hub.radius * 1e3:g} mm; hub rotation {config.coiling.hub_angle:g} rad"
    )
    rows = [(p.label, *_display(p.value, p.unit), p.source) for p in preds]
    w0 = max(len(r[0]) for r in rows)
    w1 = max(len(r[1]) for r in rows)
    w2 = max(len(r[2]) for r in rows)
    echo()
    for label, value, unit, source in rows:
        echo(f"  {label:<{w0}}  {value:>{w1}} {unit:<{w2}}  {source}")
    return 0


def cmd_config(args: argparse.Namespace) -> int:
    echo(to_toml(load_config(args.config)).rstrip())
    return 0
