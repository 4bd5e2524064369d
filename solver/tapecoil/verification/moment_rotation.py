"""A tape spring's whole moment-rotation curve in opposite-sense and equal-sense bending, its
stable and unstable branches, by arc-length continuation (:mod:`tapecoil.core.arclength`) and
the stability of each state (:mod:`tapecoil.core.stability`).

The tape of the configuration (its section, its wall: isotropic or laminated), a piece of
``length``, is bent by end rotations: each end section is turned rigidly about the width axis,
free to approach the other (a pure moment), held laterally at its centre. The end rotation
between the two ends, phi, is the load parameter; the moment is the energy's derivative in it,
M = dE/dphi at the state held (its partial derivative: the free dofs are at equilibrium).
Half of the tape is solved, on the plane of symmetry through its middle, where the fold forms;
its stability is judged against the deformations that keep that symmetry (the fold shifting
along the tape is left out: on a uniform tape that motion is neutral, and its eigenvalue near
zero would blur every other one).

The curve is followed in three parts (Seffen and Pellegrino 1999, Fig. 5: O-A, A-B, B-C, C-D):

1. the **primary branch** from rest, arc length with the stability of every state, to its
   first critical point A (a limit point or a bifurcation, the eigenvalue through zero there):
   the **peak moment** is the largest moment on it, the **snap rotation** is A's;
2. the **snap** at that rotation (pseudo-transient relaxation, as the tape jumps under a
   rotation held) onto the fold branch, which is then stepped to the end rotation;
3. the **return**: arc length back from the end rotation along the fold branch, through its
   limit point D (where the fold vanishes under a falling rotation, the eigenvalue through zero
   there) and on along the unstable branch that joins A, until its moment is back at A's.

The **steady fold moment** is the mean moment over the fold branch's last 2 h_e / R of rotation
(h_e the element length: about a period of its wavering as the fold's ends cross the elements),
against alpha (sqrt(D11 D22) +- D12), (1 +- nu) D alpha for an isotropic wall (Wuest 1954;
Seffen and Pellegrino 1999; physics brief Sec. 10). The peak moments and the snap rotations
are predictions: no published value for this tape and these end conditions was found to check
them against.
"""

from __future__ import annotations

import math
import time

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from tapecoil import theory
from tapecoil.config import Config
from tapecoil.core import jit
from tapecoil.core.arclength import ArcLength, ArcLengthError, ArcLengthSettings
from tapecoil.core.dofs import global_scalar, global_size
from tapecoil.core.newton import SNESSolver
from tapecoil.core.path_system import SolverSystem
from tapecoil.core.stability import StabilityAnalysis
from tapecoil.core.stepping import Continuation, Relaxation
from tapecoil.geometry.meshes import FREE_END, ROOT, MeshResolution, create_strip_mesh
from tapecoil.geometry.surfaces import StripGeometry
from tapecoil.models.edges import RigidSection
from tapecoil.models.shell import NaghdiShell, shell_material
from tapecoil.models.solver_terms import relaxation_scale
from tapecoil.models.supports import fixed_point, symmetry_plane
from tapecoil.verification.checks import CaseResult, Check, solver_prefix

SENSES = ("opposite", "equal")
# the tape's length over its section radius R, when the configured tape is longer: the fold and
# the transitions on either side of it stay clear of the ends
LENGTH_OVER_R = 16.0
# the end rotation the curve is followed to [rad]: the fold grown to about R phi along the tape
END_ANGLE = 2.0
# the end rotations the case defines [rad]: beyond pi the two arms would pass through each other
ANGLE_RANGE = (0.0, math.pi)
# (elements across the arc width, elements along per section radius R)
FOLD_MESHES = {"coarse": (8, 4.0), "default": (12, 6.0), "fine": (16, 8.0)}
FOLD_MOMENT_TOLERANCE = 0.03


def fold_resolution(preset: str, R: float, length: float) -> MeshResolution:
    """The mesh of the half tape (``length`` / 2) of the preset ``preset``."""
    across, per_R = FOLD_MESHES[preset]
    return MeshResolution(across=across, along=max(2, round(length / 2 / R * per_R)))


class BentTape:
    """Half of a tape piece bent by its end rotations (see the module): the shell, its supports,
    its solver and the end rotation phi as the load parameter (collective).

    ``sense``: "opposite" (the section flattens) or "equal"; ``length`` [m]: the whole piece's.
    """

    def __init__(
        self,
        config: Config,
        sense: str,
        resolution: MeshResolution,
        length: float,
        comm=MPI.COMM_WORLD,
        name: str = "tape_moment_rotation",
    ):
        if sense not in SENSES:
            raise ValueError(f"moment-rotation: sense {sense!r} must be one of {SENSES}")
        tp = config.tape
        if not (math.isfinite(length) and 0 < length <= tp.L):
            raise ValueError(f"moment-rotation: length {length} m must lie in (0, tape.L = {tp.L}] m")
        self.config, self.sense, self.length = config, sense, length
        self.sign = theory.sense_sign(sense)
        strip = create_strip_mesh(comm, StripGeometry(tp.R, tp.b, length / 2), resolution)
        self.model = model = NaghdiShell(strip, shell_material(config), director_frame="global")
        self.resolution = resolution
        # x = 0: the turned end, held laterally at its centre; x = length / 2: the middle
        self.end = RigidSection(
            model, ROOT, axis=np.array([0.0, 1.0, 0.0]), stiffness=100 * config.wall.axial_modulus * tp.h
        )
        middle = symmetry_plane(model, strip.facet_tags.find(FREE_END), (1.0, 0.0, 0.0), "the middle")
        self.bcs = self.end.bcs + middle + fixed_point(model, (0.0, 0.0), "yz")
        self.energy = model.strain_energy + self.end.energy
        self.h_e = length / 2 / resolution.along
        self.viscosity, previous, viscous = model.relaxation(length_scale=self.h_e)
        self.previous = previous
        self.relaxation_scale = relaxation_scale(config.wall.bending, self.h_e)
        F = ufl.derivative(self.energy, model.q, model.dq) + viscous
        self.prefix = solver_prefix(name)
        self.solver = SNESSolver.from_config(
            F,
            model.jacobian_form(F),
            model.q,
            self.bcs,
            config.solver,
            prefix=self.prefix,
            state_scale=model.rounding_scale(),
        )
        self._energy_form = jit.form(self.energy)
        self.angle = 0.0

    def set_angle(self, phi: float) -> None:
        """The end rotation phi [rad] between the whole tape's ends: each end turned by phi / 2,
        the half solved here by -phi / 2 against its middle (the sense in phi's sign)."""
        self.end.set(-self.sign * phi / 2)
        self.angle = phi

    def moment(self) -> float:
        """M = dE/dphi [N m] at the state held, the whole tape's (collective): a central
        difference of the energy with the free dofs held and the turned end's moved."""
        q = self.model.q
        saved = q.x.array.copy()
        phi, h = self.angle, 1e-6
        values = []
        try:
            for trial in (phi + h, phi - h):
                self.set_angle(trial)
                for bc in self.end.bcs:
                    bc.set(q.x.array)
                q.x.scatter_forward()
                values.append(global_scalar(self._energy_form, q.function_space.mesh.comm))
        finally:
            q.x.array[:] = saved
            self.set_angle(phi)
        # the half tape holds half the energy
        return 2.0 * (values[0] - values[1]) / (2 * h)

    def destroy(self) -> None:
        self.solver.destroy()


def moment_rotation_curve(
    config: Config,
    sense: str,
    resolution: MeshResolution,
    length: float,
    end_angle: float = END_ANGLE,
    comm=MPI.COMM_WORLD,
    *,
    first_step: float = 2e-3,
    max_points: int = 300,
    name: str = "tape_moment_rotation",
) -> dict:
    """The moment-rotation curve of the configured tape in ``sense`` up to ``end_angle`` [rad]
    (see the module): its branches as rows (branch, phi [rad], M [N m], stable, the eigenvalue
    nearest zero), the located critical points, the peak moment, the snap rotation, where the
    fold vanishes, the steady fold moment, counts and wall times (collective).

    ``first_step`` [rad]: the first arc-length step's rotation (positive); ``max_points``: the
    most points of each arc-length run. Moments are the magnitudes, in either sense.
    """
    lo, hi = ANGLE_RANGE
    if not (math.isfinite(end_angle) and lo < end_angle <= hi):
        raise ValueError(
            f"moment-rotation: end angle {end_angle} rad must lie in ({lo:g}, pi]: beyond pi the "
            "tape's two arms would pass through each other"
        )
    if not (math.isfinite(first_step) and 0 < first_step < end_angle):
        raise ValueError(
            f"moment-rotation: first step {first_step} rad must be positive and below the end angle "
            f"{end_angle} rad"
        )
    t_start = time.perf_counter()
    tape = BentTape(config, sense, resolution, length, comm, name)
    stability = StabilityAnalysis(3, prefix=f"{tape.prefix}stability_")
    system = SolverSystem(tape.solver, tape.set_angle, load_range=ANGLE_RANGE)
    rows: list[tuple] = []
    critical: list[tuple] = []
    iterations: dict[str, int] = {}
    times: dict[str, float] = {}
    ended = "no snap"

    def follow(part: str, start: float, end: float, step: float, stop=None, until_critical=False):
        """An arc-length run from the state in place, its points and critical points recorded."""
        settings = ArcLengthSettings(first_step=step, max_step=10.0, min_step=1e-6, max_points=max_points)
        path = ArcLength(system, settings, stability=stability)
        t0 = time.perf_counter()

        def on_point(point):
            if rows and rows[-1][0] == part and point.arc_length == 0.0:
                return  # the start, recorded already as the end of the branch before
            rows.append((part, point.load, tape.moment(), point.stable, _nearest(point.eigenvalues)))

        try:
            path.run(
                start,
                end,
                on_point=on_point,
                stop=None if stop is None else lambda p: stop(path, p),
                until_critical=until_critical,
            )
            how = "end"
        except ArcLengthError as exc:
            how = f"stopped: {exc}"
        finally:
            iterations[part] = iterations.get(part, 0) + path.timings["iterations"]
            times[part] = times.get(part, 0.0) + time.perf_counter() - t0
        for c in path.critical:
            system.set_state(c.state, c.load)
            critical.append(
                (part, c.kind, c.load, tape.moment(), c.eigenvalue / c.initial_eigenvalue, c.mode)
            )
        x = system.vector()
        system.get_state(x)
        last = path.points[-1].load
        path.destroy()
        system.set_state(x, last)
        return how, last

    try:
        # 1. the primary branch to its first critical point
        how, phi_A = follow("primary", 0.0, end_angle, first_step, until_critical=True)
        if not any(c[0] == "primary" for c in critical):
            raise ArcLengthError(f"moment-rotation: no critical point on the primary branch ({how})", phi_A)
        # 2. the snap: off A along its critical mode (the side of lower energy), relaxed at a
        # rotation just past it down to the fold branch
        t0 = time.perf_counter()
        snapped, snap_iterations = _snap(tape, system, critical[-1], config)
        iterations["snap"], times["snap"] = snap_iterations, time.perf_counter() - t0
        if not snapped:
            raise ArcLengthError("moment-rotation: the relaxation past the snap found no stable state", phi_A)
        result = stability.analyse(tape.solver.compute_jacobian(), system.held_rows())
        phi_B = tape.angle
        rows.append(("fold", phi_B, tape.moment(), result.stable, _nearest(result.eigenvalues)))
        # 3. the fold branch stepped to the end rotation (stable: steps suffice, relaxed through
        # any further snap), then back by arc length through D and on to A
        t0 = time.perf_counter()
        relax = Relaxation(tape.viscosity, tape.previous, scale=tape.relaxation_scale, max_iterations=400)
        control = config.solver.control(initial_step=0.01, max_step=0.02, min_step=1e-4, max_cutbacks=4)

        def stepped(step):
            judged = stability.analyse(tape.solver.compute_jacobian(), system.held_rows())
            rows.append(("fold", step.load, tape.moment(), judged.stable, _nearest(judged.eigenvalues)))
            iterations["fold"] = iterations.get("fold", 0) + step.total_iterations

        try:
            Continuation(
                tape.solver.solve, tape.set_angle, tape.model.q, control, relaxation=relax, on_step=stepped
            ).run(phi_B, end_angle)
        finally:
            times["fold"] = time.perf_counter() - t0
        M_A = next(c[3] for c in critical if c[0] == "primary")

        def joined(path, _point) -> bool:
            # D located: the critical points of the unstable branch beyond are not sought
            path.locate = not any(c.kind == "limit" for c in path.critical)
            return rows[-1][2] >= M_A

        ended, _ = follow("return", end_angle, 0.0, -first_step, stop=joined)
        if rows[-1][2] >= M_A:
            ended = "joined the primary branch"
    finally:
        tape.destroy()
    return _summary(config, tape, rows, critical, iterations, times, ended, t_start, length, end_angle)


def _snap(tape: BentTape, system: SolverSystem, critical: tuple, config: Config) -> tuple[bool, int]:
    """From the critical state in place (``critical``'s mode), the state a little off it along
    the mode (its largest component a tenth of the thickness), on the side of lower energy,
    relaxed at a rotation 1 % past the critical one."""
    q = tape.model.q
    x = system.vector()
    system.get_state(x)
    mode = critical[5]
    # the mode scaled to a tenth of the thickness at its largest
    scale = 0.1 * config.tape.h / max(mode.norm(PETSc.NormType.NORM_INFINITY), 1e-300)
    phi = critical[2] * 1.01
    energies = []
    for sign in (1.0, -1.0):
        trial = x.copy()
        trial.axpy(sign * scale, mode)
        system.set_state(trial, phi)
        for bc in tape.bcs:
            bc.set(q.x.array)
        q.x.scatter_forward()
        energies.append((global_scalar(tape._energy_form, q.function_space.mesh.comm), sign, trial))
    _, _, start = min(energies, key=lambda e: e[0])
    system.set_state(start, phi)
    relax = Relaxation(tape.viscosity, tape.previous, scale=tape.relaxation_scale, max_iterations=400)
    control = config.solver.control(initial_step=0.01, max_step=0.01, min_step=1e-4)
    return Continuation(tape.solver.solve, tape.set_angle, q, control, relaxation=relax).settle(phi)


def _nearest(eigenvalues) -> float:
    return float(min(eigenvalues, key=abs)) if eigenvalues else math.nan


def _summary(config, tape, rows, critical, iterations, times, ended, t_start, length, end_angle) -> dict:
    tp = config.tape
    reference = theory.fold_moment(config.wall.bending, tp.alpha, tape.sense)
    primary = [r for r in rows if r[0] == "primary"]
    peak = max(primary, key=lambda r: r[2])
    snap = next((c for c in critical if c[0] == "primary"), None)
    # D: where the fold branch, followed back, turns (the first limit point of the return)
    vanish = next((c for c in critical if c[0] == "return" and c[1] == "limit"), None)
    # the fold branch over about the last period of its wavering: the fold's moment wavers as its
    # ends cross the elements, about once each time its half-length R phi / 2 grows by an
    # element, 2 h_e / R of rotation; the mean of M over phi there (the energy's secant) evens
    # most of it out
    period = 2 * tape.h_e / tp.R
    steady_rows = [r for r in rows if r[0] == "fold" and r[1] >= end_angle - period - 1e-12]
    steady = math.nan
    if len(steady_rows) > 1:
        phi, M = np.array([r[1] for r in steady_rows]), np.array([r[2] for r in steady_rows])
        steady = float(np.sum(0.5 * (M[1:] + M[:-1]) * np.diff(phi)) / (phi[-1] - phi[0]))
    res = tape.resolution
    return {
        "sense": tape.sense,
        "length": length,
        "end_angle": end_angle,
        "mesh": f"{res.along} x {res.across} (half tape)",
        "dofs": global_size(tape.model.W),
        "rows": [(part, float(phi), float(M), stable, float(eig)) for part, phi, M, stable, eig in rows],
        "critical": [
            {
                "branch": b,
                "kind": k,
                "rotation": float(phi),
                "moment": float(M),
                "eigenvalue_over_rest": float(e),
            }
            for b, k, phi, M, e, _ in critical
        ],
        "peak_moment": float(peak[2]),
        "peak_rotation": float(peak[1]),
        "snap_rotation": float(snap[2]) if snap else math.nan,
        "snap_moment": float(snap[3]) if snap else math.nan,
        "snap_kind": snap[1] if snap else None,
        "snap_eigenvalue_over_rest": float(snap[4]) if snap else math.nan,
        "fold_vanishes_rotation": float(vanish[2]) if vanish else math.nan,
        "fold_vanishes_moment": float(vanish[3]) if vanish else math.nan,
        "fold_vanishes_eigenvalue_over_rest": float(vanish[4]) if vanish else math.nan,
        "steady_fold_moment": steady,
        "steady_states": len(steady_rows),
        "steady_from": end_angle - period,
        "fold_moment_reference": reference,
        "return_ended": ended,
        "points": {part: sum(1 for r in rows if r[0] == part) for part in ("primary", "fold", "return")},
        "newton_iterations": iterations,
        "wall_times": times,
        "wall_time": time.perf_counter() - t_start,
    }


def tape_moment_rotation(
    config: Config,
    preset: str = "coarse",
    comm=MPI.COMM_WORLD,
    *,
    length: float | None = None,
    end_angle: float = END_ANGLE,
    senses: tuple[str, ...] = SENSES,
) -> CaseResult:
    """The verification case ``tape-moment-rotation`` (collective): the configured tape's
    moment-rotation curve in each sense (:func:`moment_rotation_curve`) on the case's mesh
    ``preset`` (:data:`FOLD_MESHES`), a piece of ``length`` (default: the tape's, at most
    :data:`LENGTH_OVER_R` R).

    Checks, each sense: the steady fold moment against the fold's moment with its free edges'
    layers (:func:`~tapecoil.theory.edge_layer.fold_moment_with_edges`), 3 %; against the plate
    form alpha (sqrt(D11 D22) +- D12) ((1 +- nu) D alpha), 3 % beyond the share the edge layers
    take off it (a shell that resolves them shows it; 3.6 % and 2.0 % for the benchmark tape);
    the eigenvalue through zero at the snap (A) and where the fold vanishes (D), below 1e-4 of
    its value at rest (the secant stops at 1e-6). The peak moments, snap rotations and the
    rotations where the folds vanish are predictions: reported, without a reference.
    """
    tp = config.tape
    length = length if length is not None else min(tp.L, LENGTH_OVER_R * tp.R)
    resolution = fold_resolution(preset, tp.R, length)
    checks, info = [], {"senses": {}, "predictions": []}
    wall = config.wall
    for sense in senses:
        curve = moment_rotation_curve(
            config, sense, resolution, length, end_angle, comm, name=f"tape_moment_rotation_{sense}"
        )
        info["senses"][sense] = curve
        steady, plate = curve["steady_fold_moment"], curve["fold_moment_reference"]
        edges = theory.fold_moment_with_edges(wall.bending, wall.axial_stiffness, tp.alpha, tp.R, sense)
        curve["fold_moment_with_edges"] = edges
        sign = "+" if sense == "opposite" else "-"
        checks += [
            Check(
                f"{sense}: steady fold moment / with edge layers", steady / edges, 1.0, FOLD_MOMENT_TOLERANCE
            ),
            Check(
                f"{sense}: steady fold moment / alpha (sqrt(D11 D22) {sign} D12)",
                steady / plate,
                1.0,
                FOLD_MOMENT_TOLERANCE + (1.0 - edges / plate),
            ),
            Check(
                f"{sense}: eigenvalue at the snap / at rest",
                curve["snap_eigenvalue_over_rest"],
                0.0,
                1e-4,
                True,
            ),
            Check(
                f"{sense}: eigenvalue where the fold vanishes / at rest",
                curve["fold_vanishes_eigenvalue_over_rest"],
                0.0,
                1e-4,
                True,
            ),
        ]
        info["predictions"] += [
            (f"{sense}: peak moment [N m]", curve["peak_moment"]),
            (f"{sense}: snap rotation [rad] ({curve['snap_kind']})", curve["snap_rotation"]),
            (f"{sense}: fold vanishes at rotation [rad]", curve["fold_vanishes_rotation"]),
        ]
    first = next(iter(info["senses"].values()))
    info.update(mesh=first["mesh"], dofs=first["dofs"], length=length, end_angle=end_angle)
    return CaseResult("tape-moment-rotation", checks, info)
