"""Arc-length continuation: the load parameter becomes an unknown, and the equilibrium path is
followed through limit points in load (snap-through) and in displacement (snap-back).

Each step solves R(x, lambda) = 0 together with Crisfield's constraint on the step's length,
|Delta x|_W^2 + psi^2 Delta lambda^2 = ds^2 (psi = 0: cylindrical), by bordered Newton
iterations: with J = dR/dx and q = dR/dlambda at the iterate, J a = -R and J b = -q share one
factorisation, the update is delta x = a + delta lambda b, and delta lambda is the root of the
constraint's quadratic that turns the step least (Crisfield 1981). The predictor follows the
path's tangent (J t = -q, normalised), oriented along the previous step so that the path does
not turn back at a limit point. The step's length adapts to the path: it grows or shrinks with
the Newton iterations it took against a target, and a step that turns the path by more than
``max_angle`` is refused and halved; a step whose Newton iterations fail is halved too.

PETSc 3.22 has the same method as SNESNEWTONAL, but petsc4py 3.22 neither names the type nor
wraps SNESNewtonALSetFunction or SNESNewtonALGetLoadParameter: a residual callback cannot learn
lambda, so neither a load that is not a constant vector (an edge turned by lambda, a hub's
angle) nor the residual assembled at lambda can be given to it. Its step length is also fixed
for the whole solve, it starts from lambda = 0 and stops at lambda_max, it returns only the
last state (no hook at each converged point, where the stability is to be judged), and a step
whose Newton iterations fail ends the solve instead of being retried shorter. So the bordering
is written here, on any :class:`~tapecoil.core.path_system.PathSystem`;
:class:`~tapecoil.core.path_system.SolverSystem` puts the project's
:class:`~tapecoil.core.newton.SNESSolver` (its assembly, its supports, its PETSc options
prefix) behind that interface.

The stability of each converged state (the tangent stiffness's eigenvalues nearest zero, and
how many are negative) is judged by :mod:`tapecoil.core.stability` when a ``stability`` is
given; where the count of negative eigenvalues changes between two states, the critical point
between them is located (a secant on the eigenvalue over the step's length) and recorded as a
limit point (the load turns back there) or a bifurcation (it does not), with its mode; a
bifurcated branch is then followed with :meth:`ArcLength.run` started along that mode.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from petsc4py import PETSc

from tapecoil.core.path_system import PathSystem
from tapecoil.core.petsc_options import DEFAULT_PETSC_OPTIONS, check_prefix, options_in_database


class ArcLengthError(RuntimeError):
    """The path could not be followed further; ``load`` is the last converged load parameter."""

    def __init__(self, message: str, load: float):
        super().__init__(message)
        self.load = load


@dataclass(frozen=True)
class ArcLengthSettings:
    """How a path is followed.

    ``first_step``: the load increment of the first step (lambda's units, its sign the
    direction the path starts in); it sets the first arc length ds0 from the tangent there.
    ``max_step``, ``min_step``: the largest and smallest arc lengths, as multiples of ds0.
    ``psi``: the weight of the load in the arc length (0: the cylindrical constraint, on the
    state alone). ``target_iterations``: Newton iterations a step should take; the next step's
    length is ds sqrt(target / taken), within [1/2, ``grow``]. ``max_iterations``: a step
    taking more fails and is halved. ``max_angle`` [rad]: the largest turn of the path between
    two steps' increments. ``rtol``, ``atol``: the residual's tolerances (relative to the
    larger of the load's norm |lambda q| and the predictor's residual, and absolute).
    ``max_points``: the most converged points a run makes.
    """

    first_step: float
    max_step: float = 20.0
    min_step: float = 1e-4
    psi: float = 0.0
    target_iterations: int = 4
    max_iterations: int = 15
    grow: float = 2.0
    max_angle: float = math.radians(15.0)
    rtol: float = 1e-9
    atol: float = 1e-12
    max_points: int = 400

    def __post_init__(self):
        if not (math.isfinite(self.first_step) and self.first_step != 0.0):
            raise ValueError(
                f"arc length: first_step {self.first_step} must be a finite, non-zero load increment"
            )
        if not (0 < self.min_step <= 1.0 <= self.max_step):
            raise ValueError(
                f"arc length: min_step ({self.min_step}) <= 1 <= max_step ({self.max_step}), both positive "
                "(multiples of the first arc length)"
            )
        if not (self.psi >= 0 and math.isfinite(self.psi)):
            raise ValueError(f"arc length: psi {self.psi} must be finite and not negative")
        if not (1 <= self.target_iterations < self.max_iterations):
            raise ValueError(
                f"arc length: 1 <= target_iterations ({self.target_iterations}) < max_iterations "
                f"({self.max_iterations})"
            )
        if not (self.grow >= 1.0 and 0 < self.max_angle < math.pi):
            raise ValueError(f"arc length: grow {self.grow} >= 1 and 0 < max_angle {self.max_angle} < pi")
        if self.max_points < 1:
            raise ValueError(f"arc length: max_points {self.max_points} must be positive")


@dataclass
class PathPoint:
    """One converged state of a path: its load parameter, the arc length walked to it (ds's
    units), the step's length, its Newton iterations, its halvings and wall time [s]; with a
    stability analysis, the eigenvalues nearest zero and the count of negative ones."""

    load: float
    arc_length: float
    step: float
    iterations: int
    halvings: int
    wall_time: float
    eigenvalues: tuple[float, ...] = ()
    negative: int | None = None

    @property
    def stable(self) -> bool | None:
        """No negative eigenvalue of the tangent stiffness (None: not judged)."""
        return None if self.negative is None else self.negative == 0


@dataclass
class CriticalPoint:
    """A state where an eigenvalue of the tangent stiffness passes through zero: ``kind`` is
    "limit" (the load turns back) or "bifurcation"; ``eigenvalue`` is the located one,
    ``initial_eigenvalue`` the same eigenvalue's value at the path's first judged state (for
    scale); ``state`` and ``mode`` are PETSc vectors of the system's layout."""

    kind: str
    load: float
    arc_length: float
    eigenvalue: float
    initial_eigenvalue: float
    state: object
    mode: object
    located_in: int  # secant iterations


@dataclass
class _Start:
    """The state a step starts from and the direction it starts in."""

    x: object
    load: float
    direction_x: object  # the previous increment (for the predictor's orientation), or None
    direction_load: float


@dataclass
class ArcLength:
    """Follows the equilibrium path of ``system`` (see the module) with ``settings``.

    ``stability``: a :class:`~tapecoil.core.stability.StabilityAnalysis` judging every converged
    state (None: not judged); ``locate``: locate the critical points where the count of
    negative eigenvalues changes. ``weights``: a vector of the state's layout weighting the
    state's part of the arc length (None: all ones).
    """

    system: PathSystem
    settings: ArcLengthSettings
    stability: object = None
    locate: bool = True
    weights: object = None
    points: list[PathPoint] = field(default_factory=list)
    critical: list[CriticalPoint] = field(default_factory=list)

    def __post_init__(self):
        check_prefix(self.system.prefix)
        s = self.system
        self._R = s.vector()
        self._q = s.vector()
        self._Rh = s.vector()
        self._a = s.vector()
        self._b = s.vector()
        self._x = s.vector()
        self._dx = s.vector()
        self._wtmp = s.vector()
        self._ksp = PETSc.KSP().create(s.comm)
        self._ksp.setOptionsPrefix(s.prefix)
        self._options = {**DEFAULT_PETSC_OPTIONS, **s.options}
        self._first_eigenvalue = None
        self.timings = {"steps": 0.0, "stability": 0.0, "locate": 0.0, "iterations": 0}

    # --- linear algebra in the arc length's metric
    def _dot(self, u, v) -> float:
        if self.weights is None:
            return u.dot(v)
        self._wtmp.pointwiseMult(u, self.weights)
        return self._wtmp.dot(v)

    def _load_tangent(self, x, load: float, R) -> None:
        """q = dR/dlambda at (x, load) by a forward difference (exact for loads linear in
        lambda; a held value moved by lambda enters through its held rows and its lifting)."""
        h = 1e-6 * max(abs(load), abs(self.settings.first_step))
        self.system.set_state(x, load + h)
        self.system.residual(self._Rh)
        self.system.set_state(x, load)
        self._Rh.axpy(-1.0, R)
        self._Rh.copy(self._q)
        self._q.scale(1.0 / h)

    def _factor(self):
        A = self.system.jacobian()
        self._ksp.setOperators(A)
        with options_in_database(self.system.prefix, self._options):
            self._ksp.setFromOptions()
            self._ksp.setUp()
        return A

    def _solve(self, rhs, out) -> bool:
        with options_in_database(self.system.prefix, self._options):
            self._ksp.solve(rhs, out)
        return self._ksp.getConvergedReason() > 0 and np.isfinite(out.norm())

    def _tangent(self, x, load: float):
        """The path's tangent at a converged (x, load): (t_x, t_lambda) with J t_x = -q t_lambda,
        normalised in the arc length's metric, t_lambda > 0."""
        s = self.system
        s.set_state(x, load)
        s.residual(self._R)
        self._load_tangent(x, load, self._R)
        self._factor()
        t = s.vector()
        self._q.scale(-1.0)
        ok = self._solve(self._q, t)
        self._q.scale(-1.0)
        if not ok:
            raise ArcLengthError(f"arc length: the tangent at load {load:.6g} could not be solved for", load)
        norm = math.sqrt(self._dot(t, t) + self.settings.psi**2)
        t.scale(1.0 / norm)
        return t, 1.0 / norm

    # --- one step
    def _attempt(self, start: _Start, ds: float, guide=None) -> tuple[bool, int, float, object]:
        """A step of arc length ``ds`` from ``start``: predictor along the tangent (or along
        ``guide`` = (vector, load part), a branch's mode), then bordered Newton on the spherical
        constraint. Returns (converged, iterations, load, increment), the state left in place."""
        s, cfg = self.system, self.settings
        psi2 = cfg.psi**2
        if guide is None:
            t, tl = self._tangent(start.x, start.load)
            if start.direction_x is None:
                sign = math.copysign(1.0, cfg.first_step)
            else:
                sign = (
                    1.0 if self._dot(t, start.direction_x) + psi2 * tl * start.direction_load >= 0 else -1.0
                )
        else:
            t, tl = guide[0].copy(), guide[1]
            norm = math.sqrt(self._dot(t, t) + psi2 * tl * tl)
            t.scale(1.0 / norm)
            tl /= norm
            sign = 1.0
        Dx = t.copy()
        Dx.scale(sign * ds)
        Dl = sign * ds * tl
        ref_x, ref_l = Dx.copy(), Dl  # the predictor: the direction the step should keep
        x = self._x
        iterations, R0 = 0, None
        while True:
            start.x.copy(x)
            x.axpy(1.0, Dx)
            load = start.load + Dl
            s.set_state(x, load)
            s.residual(self._R)
            rnorm = self._R.norm()
            self._load_tangent(x, load, self._R)
            if R0 is None:
                R0 = rnorm
            tol = max(cfg.atol, cfg.rtol * max(abs(load) * self._q.norm(), R0))
            if not np.isfinite(rnorm) or rnorm > 1e8 * max(R0, tol):
                return False, iterations, load, Dx
            if (rnorm <= tol and iterations > 0) or rnorm <= cfg.atol:
                return True, iterations, load, Dx
            if iterations >= cfg.max_iterations:
                return False, iterations, load, Dx
            iterations += 1
            self.timings["iterations"] += 1
            self._factor()
            self._R.scale(-1.0)
            self._q.scale(-1.0)
            if not (self._solve(self._R, self._a) and self._solve(self._q, self._b)):
                return False, iterations, load, Dx
            # |Dx + a + dl b|^2 + psi^2 (Dl + dl)^2 = ds^2
            self._a.axpy(1.0, Dx)  # a <- Dx + a
            A = self._dot(self._b, self._b) + psi2
            B = 2.0 * (self._dot(self._b, self._a) + psi2 * Dl)
            C = self._dot(self._a, self._a) + psi2 * Dl * Dl - ds * ds
            disc = B * B - 4.0 * A * C
            if disc < 0:
                return False, iterations, load, Dx
            root = math.sqrt(disc)
            q = -0.5 * (B + math.copysign(root, B))
            roots = [q / A, C / q] if q != 0 else [-B / (2 * A)]
            best, best_cos = None, -math.inf
            for dl in roots:
                # the increment this root makes, against the predictor's direction
                cos = self._dot(self._a, ref_x) + dl * self._dot(self._b, ref_x) + psi2 * (Dl + dl) * ref_l
                if cos > best_cos:
                    best, best_cos = dl, cos
            self._a.copy(Dx)
            Dx.axpy(best, self._b)
            Dl += best

    # --- the path
    def _judge(self, point: PathPoint) -> None:
        if self.stability is None:
            return
        t0 = time.perf_counter()
        A = self.system.jacobian()
        result = self.stability.analyse(A, self.system.held_rows())
        point.eigenvalues = tuple(result.eigenvalues)
        point.negative = result.negative
        if self._first_eigenvalue is None and result.eigenvalues:
            self._first_eigenvalue = result.eigenvalues[0]
        self.timings["stability"] += time.perf_counter() - t0

    def _locate(
        self, start: _Start, ds: float, before: PathPoint, after: PathPoint, guide
    ) -> CriticalPoint | None:
        """The critical point between ``before`` (at ``start``) and ``after`` (at ds from it): a
        secant (Illinois) on the eigenvalue nearest zero over the step's length."""
        t0 = time.perf_counter()

        def crossing(p: PathPoint) -> float:
            # the eigenvalue nearest zero, signed as the count of negative ones says which side
            # of the crossing p lies on (the nearest one need not be the crossing one far from it)
            value = abs(min(p.eigenvalues, key=abs))
            return value if p.negative == before.negative else -value

        a, fa = 0.0, crossing(before)
        b, fb = ds, crossing(after)
        side = 0
        best = None
        scale = abs(self._first_eigenvalue or fa) or 1.0
        it = 0
        for it in range(1, 25):  # noqa: B007 (the count is reported)
            c = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
            if not (min(a, b) < c < max(a, b)):
                c = 0.5 * (a + b)
            ok, _, load, Dx = self._attempt(start, c, guide)
            if not ok:
                break
            A = self.system.jacobian()
            result = self.stability.analyse(A, self.system.held_rows(), vectors=True)
            nearest = min(result.eigenvalues, key=abs)
            fc = abs(nearest) if result.negative == before.negative else -abs(nearest)
            best = (c, load, nearest, result, Dx.copy())
            if abs(fc) <= 1e-6 * scale or abs(b - a) <= 1e-9 * ds:
                break
            if fc * fb < 0:
                a, fa = b, fb
                side = 0
            else:
                if side == 1:
                    fa *= 0.5
                side = 1
            b, fb = c, fc
        self.timings["locate"] += time.perf_counter() - t0
        if best is None:
            return None
        c, load, fc, result, Dx = best
        state = self.system.vector()
        self.system.get_state(state)
        return CriticalPoint(
            kind="bifurcation",
            load=load,
            arc_length=before.arc_length + c,
            eigenvalue=fc,
            initial_eigenvalue=self._first_eigenvalue if self._first_eigenvalue is not None else fa,
            state=state,
            mode=result.mode,
            located_in=it,
        )

    def run(
        self,
        load_start: float,
        load_end: float,
        *,
        load_min: float = -math.inf,
        stop: Callable[[PathPoint], bool] | None = None,
        on_point: Callable[[PathPoint], None] | None = None,
        along=None,
        previous=None,
        first_arc_length: float | None = None,
        until_critical: bool = False,
    ) -> list[PathPoint]:
        """Follow the path from the state in place at ``load_start`` until the load reaches
        ``load_end`` (the last point lands on it exactly), falls below ``load_min``, ``stop(point)``
        is true, or ``settings.max_points`` points are made. ``on_point(point)`` after each
        converged point, the state in place. ``along`` = (vector, load part): the first step
        leaves along it (a bifurcated branch's mode) instead of the tangent; ``previous`` =
        (vector, load part): the increment the path arrived with (orients the first tangent).
        ``first_arc_length``: the first step's arc length, instead of the one ``first_step``
        gives along the tangent (needed with ``along``: at a critical point the tangent is
        singular). ``until_critical``: end on the first critical point located, accepted (and
        committed) as the last point: a branch is switched to from there (a beam's rotations
        are increments from the last accepted state, so the critical state must be accepted
        before a run leaves it along its mode).
        Raises :class:`ArcLengthError` when no step converges, the state then the last converged.
        """
        lo, hi = self.system.load_range
        for name, value in (("load_start", load_start), ("load_end", load_end)):
            if not math.isfinite(value) or not lo <= value <= hi:
                raise ValueError(f"arc length: {name} {value} lies outside the problem's loads [{lo}, {hi}]")
        if not load_min < load_start:
            raise ValueError(f"arc length: load_min {load_min} must lie below load_start {load_start}")
        load_min = max(load_min, lo)
        if (load_end - load_start) * self.settings.first_step <= 0:
            raise ValueError(
                f"arc length: the first step {self.settings.first_step} must point from load_start "
                f"{load_start} towards load_end {load_end}"
            )
        if first_arc_length is not None and not (math.isfinite(first_arc_length) and first_arc_length > 0):
            raise ValueError(f"arc length: first_arc_length {first_arc_length} must be positive")
        cfg, s = self.settings, self.system
        x0 = s.vector()
        s.get_state(x0)
        start = _Start(x0, load_start, None, 0.0)
        if previous is not None:
            start.direction_x, start.direction_load = previous[0].copy(), previous[1]
        # ds0 from the first load increment along the tangent
        if first_arc_length is None:
            _, tl = self._tangent(x0, load_start)
            ds0 = abs(cfg.first_step) / tl
        else:
            ds0 = first_arc_length
        s.set_state(x0, load_start)
        ds, arc = ds0, 0.0
        guide = along
        first = PathPoint(load_start, 0.0, 0.0, 0, 0, 0.0)
        self._judge(first)
        self.points.append(first)
        if on_point is not None:
            on_point(first)
        previous_point = first
        landing = False
        while len(self.points) < cfg.max_points + 1:
            t0 = time.perf_counter()
            halvings = 0
            while True:
                ok, its, load, Dx = self._attempt(start, ds, guide)
                turned = False
                if ok and start.direction_x is not None and guide is None:
                    cos = (
                        self._dot(Dx, start.direction_x)
                        + cfg.psi**2 * (load - start.load) * start.direction_load
                    ) / (
                        ds
                        * math.sqrt(
                            self._dot(start.direction_x, start.direction_x)
                            + cfg.psi**2 * start.direction_load**2
                        )
                    )
                    turned = math.acos(max(-1.0, min(1.0, cos))) > cfg.max_angle
                if ok and not turned:
                    break
                ds *= 0.5
                halvings += 1
                if ds < cfg.min_step * ds0:
                    s.set_state(start.x, start.load)
                    why = "turns too sharply" if turned else "does not converge"
                    raise ArcLengthError(
                        f"arc length: the path {why} at load {start.load:.6g} even at the smallest step",
                        start.load,
                    )
            if load > load_end if load_end > load_start else load < load_end:
                # overshot: land on load_end by a shorter step (secant on the step's length)
                landing = True
                ds_land = ds * (load_end - start.load) / (load - start.load)
                ok, its2, load2, Dx2 = self._attempt(start, ds_land, guide)
                if ok:
                    ok, its3, load, Dx = self._land(start, Dx2, load2, load_end)
                    its += its2 + its3
                    ds = ds_land
                if not ok:
                    s.set_state(start.x, start.load)
                    raise ArcLengthError(f"arc length: could not land on load {load_end}", start.load)
            arc += ds
            point = PathPoint(load, arc, ds, its, halvings, 0.0)
            self._judge(point)
            if (
                self.locate
                and self.stability is not None
                and point.negative is not None
                and previous_point.negative is not None
                and point.negative != previous_point.negative
            ):
                x_after = s.vector()
                s.get_state(x_after)
                critical = self._locate(start, ds, previous_point, point, guide)
                if critical is not None:
                    turn = (critical.load - start.load) * (load - critical.load) < 0
                    critical.kind = "limit" if turn else "bifurcation"
                    self.critical.append(critical)
                    if until_critical:
                        # end on the critical state itself, accepted as the path's last point
                        s.set_state(critical.state, critical.load)
                        arc += critical.arc_length - point.arc_length
                        point = PathPoint(critical.load, critical.arc_length, ds, its, halvings, 0.0)
                        point.eigenvalues, point.negative = (critical.eigenvalue,), previous_point.negative
                        load = critical.load
                        landing = True
                        s.get_state(x_after)
                        Dx = x_after.copy()
                        Dx.axpy(-1.0, start.x)
                s.set_state(x_after, load)
            point.wall_time = time.perf_counter() - t0
            self.timings["steps"] += point.wall_time
            s.commit(load)
            s.get_state(start.x)
            start.direction_x = Dx.copy()
            start.direction_load = load - start.load
            start.load = load
            guide = None
            self.points.append(point)
            previous_point = point
            if on_point is not None:
                on_point(point)
            if landing or load < load_min or (stop is not None and stop(point)):
                break
            factor = math.sqrt(cfg.target_iterations / max(its, 1))
            ds = min(max(ds * min(cfg.grow, max(0.5, factor)), cfg.min_step * ds0), cfg.max_step * ds0)
        return self.points

    def _land(self, start: _Start, Dx, load: float, target: float):
        """Newton at the fixed load ``target`` from the state start + Dx (a step's end moved
        onto the load it is to end at)."""
        s, cfg = self.system, self.settings
        x = self._x
        start.x.copy(x)
        x.axpy(1.0, Dx)
        its, R0 = 0, None
        while True:
            s.set_state(x, target)
            s.residual(self._R)
            rnorm = self._R.norm()
            if R0 is None:
                R0 = rnorm
                self._load_tangent(x, target, self._R)
                scale = abs(target) * self._q.norm()
            if (rnorm <= max(cfg.atol, cfg.rtol * max(scale, R0)) and its > 0) or rnorm <= cfg.atol:
                Dx = x.copy()
                Dx.axpy(-1.0, start.x)
                return True, its, target, Dx
            if its >= cfg.max_iterations or not np.isfinite(rnorm):
                return False, its, target, Dx
            its += 1
            self._factor()
            self._R.scale(-1.0)
            if not self._solve(self._R, self._a):
                return False, its, target, Dx
            x.axpy(1.0, self._a)

    def destroy(self) -> None:
        """Free the linear solver, and the system's own objects (a solver made for the path)."""
        self._ksp.destroy()
        release = getattr(self.system, "destroy", None)
        if release is not None:
            release()
