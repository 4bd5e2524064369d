"""What a coiling run is measured by: the coil's energy, curvatures, stresses, radii and ploy region.

Each measure is read from the converged state and compared with the plate theory of the
physics brief (:mod:`tapecoil.theory`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import ufl

from tapecoil import theory
from tapecoil.core.dofs import cell_midpoint_values, global_scalar
from tapecoil.measures.deployment import lift_off
from tapecoil.measures.interlayer import coil_interlayer
from tapecoil.measures.measure import Measure

# ``tape`` below: a tape on its hub as the phases hold it (tapecoil.phases.tape_on_hub.TapeOnHub),
# read, never named: the measures sit below the phases


def _ramps(psi: np.ndarray, ramp_width: float, margin: float) -> np.ndarray:
    """True where psi lies in (or within ``margin`` of) a climb over the root step."""
    phase = np.mod(psi, 2 * math.pi)
    return (phase >= 2 * math.pi - ramp_width - margin) | (phase <= margin)


def ploy_measure(tape, coiled=None, xi1=None, xi2=None, k_trans=None) -> dict:
    """The ploy (transition) region at the current state against physics.md Sec. 7 (collective).

    Along the cells next to the centre line beyond the tangent point: the length over which the
    transverse curvature rises from 0.1/R to 0.9/R. None when the free part is too short for
    the section to recover (near the end of the coiling run). Cell values may be passed in.
    """
    tp = tape.config.tape
    beta = tape.config.wall.bending.beta
    if coiled is None:
        coiled = tape.coil_geometry(tape.root.angle)["coiled_length"]
        _, cells = cell_midpoint_values(tape.model.mesh, [tape.model.curvatures()[1]])
        cells = np.vstack(tape.comm.allgather(cells))
        xi1, xi2, k_trans = cells[:, 0], cells[:, 1], cells[:, 2]
    centre = np.abs(xi2) <= np.min(np.abs(xi2)) + 1e-9
    order = np.argsort(xi1[centre])
    s_line, kt_line = xi1[centre][order], k_trans[centre][order] * tp.R
    beyond = s_line > coiled
    ploy = None
    if beyond.any():
        s_b, kt_b = s_line[beyond], kt_line[beyond]
        high = np.nonzero(kt_b >= 0.9)[0]
        if len(high):
            low = np.nonzero(kt_b[: high[0] + 1] <= 0.1)[0]
            start = s_b[low[-1]] if len(low) else coiled
            ploy = float(s_b[high[0]] - start)
    return {
        "computed": ploy,
        "hub_angle": tape.root.angle,
        "reference_arc_width": theory.ploy_length(tp.b, tp.R, tp.h, beta),
        "reference_projected_width": theory.ploy_length(2 * tp.R * math.sin(tp.alpha / 2), tp.R, tp.h, beta),
        "free_length": tp.L - coiled,
        "quantity": "centre line, transverse curvature from 0.1/R to 0.9/R",
        "profile": {"xi1": s_line.tolist(), "kappa_trans_R": kt_line.tolist()},
    }


def coil_measures(tape, cells: dict | None = None) -> dict:
    """Measured quantities of the coil at the current state against physics.md (collective).

    ``cells``: :func:`coiled_cells` of the current state, if the caller has them already.

    Returns a dict of named entries {computed, reference, error, ...}, plus profiles along the
    centre line. The "coiled interior" is the wound material more than one radian from the root
    and from the tangent point, away from the climbs over the root step, over the inner 60 % of
    the width (the thesis's comparison region; the free edges carry a boundary layer).
    """
    cfg = tape.config
    tp, r_hub, h = cfg.tape, tape.r_hub, cfg.tape.h
    m, contact = tape.model, tape.contact
    angle = tape.root.angle
    geometry = tape.coil_geometry(angle)
    coiled = geometry["coiled_length"]
    out: dict = {"hub_angle": angle, "coiled_length": coiled}
    # the free fraction by the deployment's lambda (lift-off from the turn beneath), which the
    # deployment starts from, and by the tangent point of the winding angles
    lifted = lift_off(tape)
    out["free_fraction"] = {
        "lambda": lifted["lambda"],
        "lift_off_coiled_length": lifted["coiled_length"],
        "tangent_point": 1.0 - coiled / tp.L,
    }

    # energy: the coiled part (psi behind the tangent point) against the plate estimate for the
    # spiral of that length; the whole tape's strain energy includes the ploy region
    wound = ufl.conditional(ufl.lt(contact.psi, angle), 1.0, 0.0)
    coiled_energy = sum(global_scalar(f, m.mesh.comm) for f in m.energy_forms(wound))
    wound_angle = theory.rotation_for_coiled_length(coiled, r_hub, h)
    sense = cfg.coiling.sense
    reference_energy = theory.stored_energy(wound_angle, r_hub, h, tp.R, tp.alpha, cfg.wall.bending, sense)
    total = tape.energies()
    plate = "plate estimate w(rho) over the coiled spiral (physics brief Sec. 3)"
    # the spiral obstacle prescribes where the turns lie; the real surfaces' contact does not
    real_turns = tape.turns is not None
    out["stored_energy_coiled"] = Measure(
        "stored strain energy of the coiled length [J]",
        coiled_energy,
        reference_energy,
        0.05,
        plate,
        "the plate estimate holds the section flat over its whole width; the free-edge boundary "
        "layers (width sqrt(R h) each, Sec. 4) and the membrane energy it neglects are a few per cent",
    ).to_dict()
    out["strain_energy_total"] = Measure(
        "strain energy of the whole tape [J]",
        total["strain"],
        reference_energy,
        None,
        plate,
        extra={"note": "includes the ploy region"},
    ).to_dict()

    # curvatures and stresses at cell midpoints
    cells = coiled_cells(tape) if cells is None else cells
    xi1, xi2, psi, k_long, k_trans = (cells[k] for k in ("xi1", "xi2", "psi", "kappa_long", "kappa_trans"))
    sx, sy = np.abs(cells["sigma_x"]), np.abs(cells["sigma_y"])
    surface = cfg.wall.stiffness_at(h / 2)
    turn = np.floor(psi / (2 * math.pi))
    rho = r_hub + h / 2 + h * turn
    interior = (
        (psi > 1.0)
        & (psi < angle - 1.0)
        & ~_ramps(psi, contact.ramp_width, 0.3)
        & (np.abs(xi2) <= 0.3 * tp.b)
    )
    if interior.any():
        curvature_ratio = np.abs(k_long[interior]) * rho[interior]
        sx_ref, sy_ref = np.abs(theory.coil_stresses(rho[interior], tp.R, surface, h / 2, sense))
        sx_ratio, sy_ratio = sx[interior] / sx_ref, sy[interior] / sy_ref
        out["cells_interior"] = int(interior.sum())
        out["curvature_longitudinal"] = Measure(
            "longitudinal curvature x turn radius (coiled interior) [-]",
            np.mean(curvature_ratio),
            1.0,
            0.05,
            "a wound turn of mid-surface radius rho = r_hub + h/2 + n h (Sec. 2) has curvature 1/rho",
            (
                "a prediction: with the real surfaces' contact nothing prescribes the turns' radii; "
                "5 % is about the element's interpolation of a circle on the coarse mesh"
                if real_turns
                else "a consistency check of the wound shape against the turn it rests on: the "
                "element's interpolation of a circle"
            ),
            extra={
                "worst": float(curvature_ratio[np.argmax(np.abs(curvature_ratio - 1))]),
                "quantity": "|kappa_long| rho (mean over the interior; worst cell)",
            },
        ).to_dict()
        out["curvature_transverse"] = {
            "computed": float(np.max(np.abs(k_trans[interior])) * tp.R),
            "reference": 0.0,
            "quantity": "max |kappa_trans| R over the interior (flattened: 0)",
        }
        stresses = "plane-stress bending of the flattened coil at z = h/2 (Sec. 4)"
        stress_basis = (
            "the thesis's shells matched the plate stresses within 17 % over the inner 60-70 % of "
            "the width; 10 % over the inner 60 % leaves the free-edge layer out"
        )
        for name, ratio, axis in (("stress_x", sx_ratio, 0), ("stress_y", sy_ratio, 1)):
            out[name] = Measure(
                f"surface stress sigma_{'xy'[axis]} / plate theory (coiled interior) [-]",
                np.mean(ratio),
                1.0,
                0.10,
                stresses,
                stress_basis,
                extra={
                    "worst": float(ratio[np.argmax(np.abs(ratio - 1))]),
                    "reference_first_turn_Pa": float(
                        theory.coil_stresses(r_hub, tp.R, surface, h / 2, sense)[axis]
                    ),
                },
            ).to_dict()

    # coil radius and the separation of successive turns (centre line, half a turn from the root)
    out["outer_radius"] = Measure(
        "outer coil radius [m]",
        geometry["outer_radius"],
        theory.outer_radius_after_rotation(angle, r_hub, h),
        0.02,
        "r_hub + h Theta / (2 pi): a growth of h per turn (Sec. 2)",
        (
            "a prediction: the turns rest on each other's real surfaces; 2 % of the radius is about 2.5 h"
            if real_turns
            else "a consistency check: the turns rest on the obstacle of the contact, which grows "
            "by h per turn; 2 % of the radius is about 2.5 h"
        ),
    ).to_dict()
    line = tape.centre_line()
    probes = [math.pi + 2 * math.pi * n for n in range(int((angle - math.pi) // (2 * math.pi)) + 1)]
    radii = np.interp(probes, line["psi"], line["radius"]) if probes else np.array([])
    out["turn_radii"] = [float(r) for r in radii]
    if len(radii) > 1:
        gaps = np.diff(radii) / h
        out["turn_separation"] = Measure(
            "radial step between turns / h [-]",
            np.mean(gaps),
            1.0,
            0.10,
            "turns one thickness apart (Sec. 2)",
            (
                "a prediction of the contact of the real surfaces: 10 % is a penetration of 0.1 h"
                if real_turns
                else "a consistency check of the contact between turns: a penetration of 0.1 h"
            ),
            extra={
                "worst": float(gaps[np.argmax(np.abs(gaps - 1))]),
                "quantity": "radial step between turns / h",
            },
        ).to_dict()
    if len(radii) and real_turns:
        ideal = r_hub + h / 2 + h * np.arange(len(radii))
        offsets = (radii - ideal) / h
        worst = int(np.argmax(np.abs(offsets)))
        out["turn_radius"] = Measure(
            "each turn's mid-surface radius - (r_hub + h/2 + n h), worst turn / h [-]",
            offsets[worst],
            0.0,
            0.2,
            "turns one thickness apart on the hub (Sec. 2)",
            "a prediction of the contact of the real surfaces, read half a turn from the root: the "
            "penalty's penetration and the fairing over the root's end, a fifth of h",
            absolute=True,
            extra={"turn": worst, "offsets": [float(v) for v in offsets]},
        ).to_dict()
    out["first_turn_radius"] = (
        Measure(
            "mid-surface radius of the first turn [m]",
            radii[0],
            r_hub + h / 2,
            None,
            "the mid-surface h/2 off the hub (Sec. 2)",
        ).to_dict()
        if len(radii)
        else None
    )

    out["ploy_length"] = ploy_measure(tape, coiled, xi1, xi2, k_trans)
    interlayer = coil_interlayer(tape)
    if interlayer is not None:
        out["pressure_jump"] = interlayer.pop("pressure_jump", None)
        out["hub_reaction"] = interlayer.pop("hub_reaction", None)
        out["interlayer"] = interlayer
    return out


def coiled_cells(tape) -> dict[str, np.ndarray]:
    """Cell-midpoint values of the current state for the pictures (collective, every rank).

    Columns: xi_1, xi_2 [m], winding angle [rad], longitudinal and transverse curvature [1/m],
    surface bending stresses sigma_x, sigma_y [Pa] (signed; see :func:`coil_measures`).
    """
    m, h = tape.model, tape.config.tape.h
    kx, ky = m.curvatures()
    # surface bending stresses (physics.md Sec. 4) from the curvature changes: the parameter
    # metric is the identity (xi_1 = x, xi_2 = arc length), so k_11 and k_22 are physical. The
    # membrane strain is left out: with reduced integration its point values are not the
    # converged field (its energy, reported in the history, is small). Q is the stiffness of
    # the wall's face at z = h/2 (the outer ply of a laminate)
    k = m.bending_strain
    Q = 0.5 * h * tape.config.wall.stiffness_at(h / 2)
    strain = (k[0, 0], k[1, 1], 2 * k[0, 1])
    stresses = [sum(Q[i, j] * strain[j] for j in range(3)) for i in (0, 1)]
    _, cells = cell_midpoint_values(m.mesh, [tape.contact.psi, kx, ky, *stresses])
    cells = np.vstack(tape.comm.allgather(cells))
    cells = cells[np.lexsort((cells[:, 1], cells[:, 0]))]
    names = ("xi1", "xi2", "psi", "kappa_long", "kappa_trans", "sigma_x", "sigma_y")
    return {name: cells[:, i] for i, name in enumerate(names)}


def hub_torque_measure(history: list[dict]) -> dict | None:
    """The hub torque read from the root's reactions against the energy balance of the steps.

    Two independent readings of one torque: the virtual work of the root's reactions in a turn
    of the hub (:meth:`CoilingProblem.hub_torque`, at each converged state) and the change of
    stored energy plus the work against the pull over each step (the history's hub_torque, a
    secant). Compared as the work each does over the run (the reaction torque integrated by
    the trapezoidal rule over the steps on which the energy balance is defined). None before
    two coiling steps.
    """
    rows = [r for r in history if r["phase"] == "coil"]
    work_reactions = work_energy = 0.0
    for before, after in itertools.pairwise(rows):
        if after["hub_torque"] == "" or before["hub_torque_reaction"] == "":
            continue
        step = after["hub_angle"] - before["hub_angle"]
        work_reactions += 0.5 * (before["hub_torque_reaction"] + after["hub_torque_reaction"]) * step
        work_energy += after["hub_torque"] * step
    if work_energy == 0.0:
        return None
    return Measure(
        "work of the hub torque from the root reactions / from the energy balance [-]",
        work_reactions / work_energy,
        1.0,
        0.03,
        "the energy balance of the steps: stored energy + work against the pull",
        "the two readings differ by the trapezoidal rule over a step (steps up to 1 rad) and the "
        "winding angles held through a step; 3 % is their sum on the coarse mesh's largest steps",
        extra={"work_reactions_J": work_reactions, "work_energy_balance_J": work_energy},
    ).to_dict()
