"""The sections of a run's configuration, one dataclass per TOML table, and :class:`Config`, all of them.

Each field is a :func:`~tapecoil.config.params.param` with its SI unit and allowed range; the
``check`` methods add what relates two fields or two sections.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from tapecoil.config.laminate import LaminateConfig
from tapecoil.config.model import ModelConfig, check_model
from tapecoil.config.params import NON_NEGATIVE, POSITIVE, ConfigError, Range, check_section, param


@dataclass
class TapeConfig:
    """The tape spring: geometry of the curved strip and its material.

    Attributes:
        R: transverse radius of the cross-section arc [m].
        alpha: angle subtended by the cross-section arc [rad], in (0, 2 pi).
        h: wall thickness [m]; must be much smaller than R (h/R <= 0.05) for shell theory.
        L: length of the tape [m].
        E: Young's modulus [Pa] of an isotropic wall (a laminate's stiffness comes from
            [laminate], and then E is not to be given).
        nu: Poisson's ratio [-], in (-1, 0.5), of an isotropic wall (as E).
        rho_l: mass per unit length [kg/m].
    """

    R: float = param(0.0151, "m", POSITIVE)
    alpha: float = param(2.3562, "rad", Range(0.0, 2 * math.pi, True, True))
    h: float = param(1.0e-4, "m", POSITIVE)
    L: float = param(0.5, "m", POSITIVE)
    E: float = param(130e9, "Pa", POSITIVE)
    nu: float = param(0.3, "-", Range(-1.0, 0.5, True, True))
    rho_l: float = param(0.0293, "kg/m", POSITIVE)

    @property
    def b(self) -> float:
        """Arc width R alpha [m]."""
        return self.R * self.alpha

    @property
    def projected_width(self) -> float:
        """Chord of the cross-section, 2 R sin(alpha/2) [m]."""
        return 2 * self.R * math.sin(self.alpha / 2)

    @property
    def D(self) -> float:
        """Flexural rigidity E h^3 / (12 (1 - nu^2)) [N m] of an isotropic wall of E and nu
        (for any wall: Config.wall.bending)."""
        return self.E * self.h**3 / (12 * (1 - self.nu**2))

    @property
    def mu(self) -> float:
        """Strain energy per unit area of the opposite-sense coil of radius R, D (1 + nu) / R^2
        [J/m^2], of an isotropic wall of E and nu (for any wall: theory.coil_energy_at_R)."""
        return self.D * (1 + self.nu) / self.R**2

    @property
    def density(self) -> float:
        """Volume density rho_l / (b h) [kg/m^3]."""
        return self.rho_l / (self.b * self.h)

    def check(self) -> None:
        if self.h / self.R > 0.05:
            raise ConfigError(
                f"tape.h = {self.h:g} m is not much smaller than tape.R = {self.R:g} m: "
                f"thin-shell theory needs h/R <= 0.05 (got {self.h / self.R:.3g})"
            )
        if self.h / self.b > 0.05:
            raise ConfigError(
                f"tape.h = {self.h:g} m is not much smaller than the arc width R*alpha = {self.b:g} m "
                f"(h/b must be <= 0.05)"
            )
        if self.L < self.b:
            raise ConfigError(f"tape.L = {self.L:g} m must be at least the arc width R*alpha = {self.b:g} m")


@dataclass
class HubConfig:
    """The rigid hub, a cylinder whose axis is parallel to the tape width, tangent to the root.

    Attributes:
        radius: hub radius r_hub (r_c in the thesis) [m].
        inertia: rotary inertia J of the hub about its axis [kg m^2], for a deployment with the
            hub free to turn (deployment.hub = 'free'); the tape's own is added by the
            simulation. 0 is a hub of negligible inertia: the coil alone resists its turning.
    """

    radius: float = param(0.0127, "m", POSITIVE)
    inertia: float = param(0.0, "kg m^2", NON_NEGATIVE)


@dataclass
class CoilingConfig:
    """Quasi-static coiling: hub rotation with a pull at the free end.

    Attributes:
        hub_angle: total hub rotation to the stowed state [rad].
        tension: pull T at the free end, along the tangent guide line [N].
        flatten_steps: load steps used to flatten the root onto the hub before rotating [-].
        predictor: initial guess of each load step: 'shift' (the state moved along the tape by
            the length wound on: steady coiling), 'secant' (extrapolated from the last two
            steps) or 'auto' (the shift where elements are at most half the hub radius long).
        max_step: largest hub-angle step [rad]; 0 takes the predictor's own (1 rad for the
            shift, 0.3 rad for the secant).
        sense: 'opposite' (the coil's longitudinal curvature opposite in sense to the section's
            transverse curvature: the hub lies on the convex side of the section, as a tape
            measure is wound) or 'equal' (the hub on the concave side) [-].
        petsc_options: PETSc options without prefix for the coiling's solver (the flattening,
            the coiling and its relaxation; prefix coil_), over [solver] petsc_options, e.g.
            {snes_monitor = ""}.
    """

    hub_angle: float = param(36.0, "rad", POSITIVE)
    tension: float = param(1.0, "N", NON_NEGATIVE)
    flatten_steps: int = param(4, "-", Range(1, 1000))
    predictor: str = param("auto", "", ("auto", "shift", "secant"))
    max_step: float = param(0.0, "rad", Range(0.0, math.pi))
    sense: str = param("opposite", "", ("opposite", "equal"))
    petsc_options: dict = param({}, "")


@dataclass
class MeshConfig:
    """Structured mesh of the strip.

    Attributes:
        preset: 'coarse' (CI), 'default' (about 4 mm elements, 9 across) or 'fine'; the fields
            below override the preset when given (> 0).
        elements_across: elements across the arc width [-] (0: from the preset).
        element_size: target element length along the tape [m] (0: from the preset).
        grading: ratio of the longest to the shortest element along the length (1: uniform) [-].
    """

    preset: str = param("default", "", ("coarse", "default", "fine"))
    elements_across: int = param(0, "-", Range(0, 200))
    element_size: float = param(0.0, "m", NON_NEGATIVE)
    grading: float = param(1.0, "-", Range(1.0, 100.0))


@dataclass
class SolverConfig:
    """Newton and the cut-back of failing steps, for every solve of every command.

    The step sizes are each phase's own, in its units: ``coiling.max_step`` [rad] and
    ``coiling.flatten_steps``, ``deployment.dt`` and ``deployment.max_dt`` [s]; the
    verification cases step their loads as their references were computed.

    Attributes:
        rtol: relative residual tolerance of Newton [-].
        atol: absolute residual tolerance of Newton [N on displacement dofs, N m on rotations].
        max_newton: Newton iterations before a step counts as failed [-].
        min_step: smallest step before a run gives up, as a fraction of the phase's whole load
            range: the hub angle, the flattening, deployment.t_end, a verification case's full
            load [-]. 0: each phase's own (1e-6 of the hub angle but at most 1e-4 rad; 1e-6 of
            the flattening; 1e-6 of t_end but at most 1e-3 deployment.dt; 1e-4 of the tape
            fold's end rotation; 1e-6 of the other cases' loads).
        grow: factor by which the step grows after an easy step [-].
        cutback: factor by which the step shrinks after a failed step [-].
        max_cutbacks: consecutive cut-backs of a failing step before the run stops or, where
            the phase can (coiling, tape fold), passes it by pseudo-transient relaxation (a
            failed relaxation is followed by further cut-backs, down to min_step) [-].
            0: each phase's own (8; the tape fold 4, so that it relaxes early through its snap).
        petsc_options: PETSc options without prefix for every solver, e.g.
            {snes_monitor = "", mat_mumps_icntl_14 = 50}; [coiling] and [deployment]
            petsc_options override them for their phase, the command line overrides both
            (-coil_snes_monitor, -deploy_..., -verify_<case>_..., the case's dashes as underscores).
        stability: judge the stability of a coiling's converged states: the lowest eigenvalue
            of the tangent stiffness with its supports (the hub held) and the count of negative
            ones in every history row, the stowed coil's lowest eigenvalues in the summary, with
            the hub held and with it free under the torque that holds it (docs/stability.md:
            what it costs, what it leaves out). The shell model's coiling and payout [-].
    """

    rtol: float = param(1e-8, "-", Range(0.0, 1.0, True, True))
    atol: float = param(1e-10, "", POSITIVE)
    max_newton: int = param(25, "-", Range(1, 1000))
    min_step: float = param(0.0, "-", Range(0.0, 1.0, hi_open=True))
    grow: float = param(1.5, "-", Range(1.0, 10.0))
    cutback: float = param(0.5, "-", Range(0.0, 1.0, True, True))
    max_cutbacks: int = param(0, "-", Range(0, 100))
    petsc_options: dict = param({}, "")
    stability: bool = param(False, "")

    def control(
        self,
        initial_step: float,
        max_step: float,
        min_step: float,
        max_cutbacks: int = 8,
        range_fraction: float = 1.0,
    ) -> StepControl:
        """The step control of a phase's continuation; steps are fractions of the span it runs over.

        ``initial_step``, ``max_step``: the phase's step limits. ``min_step``, ``max_cutbacks``:
        the phase's own, used where this section leaves them at 0. ``range_fraction``: the
        phase's whole load range over the span, the unit of this section's ``min_step``.
        """
        return StepControl(
            initial_step=initial_step,
            max_step=max_step,
            min_step=self.min_step * range_fraction if self.min_step > 0 else min_step,
            grow=self.grow,
            cutback=self.cutback,
            max_cutbacks=self.max_cutbacks or max_cutbacks,
        )


@dataclass(frozen=True)
class StepControl:
    """The load stepping of one continuation (:class:`tapecoil.core.stepping.Continuation`).

    Not a configuration section: :meth:`SolverConfig.control` makes it from ``[solver]`` and a
    phase's step limits. Steps are fractions of the span the continuation runs over [-].
    """

    initial_step: float
    max_step: float
    min_step: float
    grow: float
    cutback: float
    max_cutbacks: int


@dataclass
class ContactConfig:
    """Penalty contact with the hub and between turns.

    Attributes:
        turns: what keeps the turns apart: 'spiral' (the ideal spiral r_hub + n h as a rigid
            obstacle, from each point's winding angle) or 'surface' (contact of the tape's real
            surfaces with each other, two-sided, from the current geometry: the turns' radii
            predicted, 3 to 6 times slower; see the README).
        penalty: penalty stiffness per unit area [N/m^3]; 0 derives it from the shell stiffness
            and the mesh size (see the contact module).
        penalty_scale: factor on the derived penalty [-].
        smoothing: width of the smoothed contact bracket as a fraction of the thickness h [-];
            0 is the plain bracket max(g, 0) (see the contact module for the trade-off).
        stop_penetration: deepest penetration of the hub or of the tape's own turns, as a
            fraction of the thickness h, that a run accepts [-], in (0, 100] (the default h: the
            faces overlap by a whole thickness and the penalty no longer holds the tape's
            shape); a step that goes deeper is cut back, and where no shorter step stays
            within it the run stops with a message naming it, the last accepted state saved.
            Equal-sense coiling starts with the section's edges inside the hub until the root
            is flattened onto it, and needs more.
        search_margin: ('surface') buffer of the contact search between turns, as a fraction of the
            thickness h [-], > 0: candidate partners within h (1 + search_margin) are kept, and
            the search is repeated only when a point has moved more than search_margin h / 2
            since the last search.
        hub_friction: Coulomb friction coefficient between the tape's face and the hub [-], in
            [0, 2]: each point pressed on the hub sticks to it until its traction reaches
            hub_friction times its pressure, then slips (a return mapping, tangential stiffness
            the normal penalty's; :mod:`tapecoil.hub.friction`); 0 frictionless. The full
            shell's coiling and its deployment with the hub held; the payout and a hub free
            to turn refuse it.
    """

    turns: str = param("spiral", "", ("spiral", "surface"))
    penalty: float = param(0.0, "N/m^3", NON_NEGATIVE)
    penalty_scale: float = param(1.0, "-", POSITIVE)
    smoothing: float = param(0.05, "-", Range(0.0, 1.0))
    stop_penetration: float = param(1.0, "-", Range(0.0, 100.0, lo_open=True))
    search_margin: float = param(2.0, "-", POSITIVE)
    hub_friction: float = param(0.0, "-", Range(0.0, 2.0))


@dataclass
class DeploymentConfig:
    """Implicit dynamic deployment from the stowed state.

    Attributes:
        t_end: simulated time [s].
        dt: initial time step [s].
        max_dt: largest time step [s]: a safety bound; the steps themselves are chosen by
            error_tolerance.
        error_tolerance: accuracy of a time step [-], in [0, 1): its estimated local error in
            the displacement (Zienkiewicz and Xie's estimate for the Newmark family) as a
            fraction of the step's own displacement; a step above it is repeated shorter, and
            the next step is sized to it. 0 leaves the steps to Newton alone (they grow after
            easy solves, up to max_dt).
        rtol: relative residual tolerance of each time step's Newton iteration [-] (the static
            phases take [solver] rtol): a step is accurate only to its own error in time, which
            the last decades of the residual do not change; [solver] atol and max_newton hold
            as well.
        release_time: time over which the hold on the free end (pull and guide) is released [s].
        rho_inf: high-frequency spectral radius of generalized-alpha [-]; 1 is trapezoidal Newmark.
        lambda_end: deployed fraction at which the run stops early [-].
        hub: 'fixed' (the hub held at its stowed angle, as in Seffen and Pellegrino's fixed-hub
            deployment) or 'free' (the hub turns on its axis with the rotary inertia
            hub.inertia, driven by the tape's torque at the root: their free-hub model) [-].
        gravity: gravitational acceleration [m/s^2], (x, y, z) in the tape's coordinates
            (x along the stowed tape's free part, y along the hub's axis, z up from the
            hub), acting from release, for comparison with ground tests; [0, 0, -9.81] hangs
            the tape below its free part's line. Default none (space).
        petsc_options: PETSc options without prefix for the deployment's solver (prefix
            deploy_), over [solver] petsc_options, e.g. {snes_monitor = ""}.
    """

    t_end: float = param(0.6, "s", POSITIVE)
    dt: float = param(1e-4, "s", POSITIVE)
    max_dt: float = param(1e-3, "s", POSITIVE)
    error_tolerance: float = param(0.0, "-", Range(0.0, 1.0, False, True))
    rtol: float = param(1e-5, "-", Range(0.0, 1.0, True, True))
    release_time: float = param(2e-3, "s", NON_NEGATIVE)
    rho_inf: float = param(0.5, "-", Range(0.0, 1.0))
    lambda_end: float = param(1.0, "-", Range(0.0, 1.0, True))
    hub: str = param("fixed", "", ("fixed", "free"))
    gravity: list = param([0.0, 0.0, 0.0], "m/s^2")
    petsc_options: dict = param({}, "")

    def newton(self, solver: SolverConfig) -> SolverConfig:
        """The solver settings of a time step: ``solver`` ([solver]) with this rtol."""
        return dataclasses.replace(solver, rtol=self.rtol)

    def check(self) -> None:
        if self.dt >= self.t_end:
            raise ConfigError(
                f"deployment.dt = {self.dt:g} s must be smaller than deployment.t_end = {self.t_end:g} s"
            )
        if self.max_dt < self.dt:
            raise ConfigError(
                f"deployment.max_dt = {self.max_dt:g} s must be at least deployment.dt = {self.dt:g} s"
            )
        if len(self.gravity) != 3:
            raise ConfigError(
                f"deployment.gravity must have three components (x, y, z), got {self.gravity!r}"
            )
        if math.hypot(*self.gravity) > 100.0:
            raise ConfigError(
                f"deployment.gravity = {self.gravity!r} m/s^2 is out of range: at most 100 m/s^2 in "
                "magnitude (ten times the Earth's; beyond, a unit is likely wrong)"
            )


@dataclass
class PayoutConfig:
    """A driven hub paying the tape out from the stowed state, quasi-static: the hub turned
    back while the free end is held in tension, the way a motorised deployer extends a boom.

    Attributes:
        lambda_end: deployed fraction to pay out to [-], in (0, 1): the hub turns back to the
            angle whose mid-surface spiral holds (1 - lambda_end) L.
        tension: the pull held at the free end [N]; 0 keeps the coiling's (coiling.tension).
        max_step: largest hub-angle step [rad]; 0 takes the coiling's (coiling.max_step, or the
            predictor's own).
    """

    lambda_end: float = param(0.9, "-", Range(0.0, 1.0, True, True))
    tension: float = param(0.0, "N", NON_NEGATIVE)
    max_step: float = param(0.0, "rad", NON_NEGATIVE)


@dataclass
class OutputConfig:
    """Where and how often results are written.

    Attributes:
        directory: results directory (created) [path].
        vtx_every: write a VTX snapshot (and a surface snapshot for the pictures) every this
            many steps [-].
        checkpoint: write the checkpoints (the stowed state, the deployed state) [-].
        checkpoint_every: also write the phase's checkpoint every this many steps, so that a
            run killed outright can resume from there [-].
        report: make the pictures and report.html at the end of a run [-].
    """

    directory: str = param("results", "")
    vtx_every: int = param(5, "-", Range(1, 10**6))
    checkpoint: bool = param(True, "")
    checkpoint_every: int = param(10, "-", Range(1, 10**6))
    report: bool = param(True, "")


@dataclass
class Config:
    """All parameters of a run, one section per TOML table."""

    tape: TapeConfig = field(default_factory=TapeConfig)
    laminate: LaminateConfig = field(default_factory=LaminateConfig)
    hub: HubConfig = field(default_factory=HubConfig)
    coiling: CoilingConfig = field(default_factory=CoilingConfig)
    model: ModelConfig = field(default_factory=ModelConfig)
    mesh: MeshConfig = field(default_factory=MeshConfig)
    solver: SolverConfig = field(default_factory=SolverConfig)
    contact: ContactConfig = field(default_factory=ContactConfig)
    deployment: DeploymentConfig = field(default_factory=DeploymentConfig)
    payout: PayoutConfig = field(default_factory=PayoutConfig)
    output: OutputConfig = field(default_factory=OutputConfig)

    def check(self) -> None:
        """Validate every section and the relations between sections."""
        for f in dataclasses.fields(self):
            check_section(f.name, getattr(self, f.name))
        if self.hub.radius <= 2 * self.tape.h:
            raise ConfigError(
                f"hub.radius = {self.hub.radius:g} m must exceed twice tape.h = {self.tape.h:g} m"
            )
        if self.hub.inertia > 0 and self.deployment.hub != "free":
            raise ConfigError(
                f"hub.inertia = {self.hub.inertia:g} kg m^2 acts only on a hub free to turn: set "
                "deployment.hub = 'free', or leave hub.inertia out for a fixed hub"
            )
        if self.solver.stability and self.contact.hub_friction > 0:
            raise ConfigError(
                f"solver.stability = true judges a tangent stiffness that has a potential, and "
                f"contact.hub_friction = {self.contact.hub_friction:g} has none: leave one of them out"
            )
        self.check_laminate()
        self.check_coiling()
        self.check_model()

    def check_laminate(self) -> None:
        """Relate the laminate to the tape (part of :meth:`check`): the plies add up to tape.h,
        and the wall stores energy in every strain."""
        lam, h = self.laminate, self.tape.h
        if lam.kind == "plies" and abs(lam.total_thickness - h) > 1e-6 * h:
            raise ConfigError(
                f"laminate.thicknesses add up to {lam.total_thickness:g} m, not tape.h = {h:g} m: the plies "
                "make the wall, so set tape.h to their sum"
            )
        if lam.kind != "isotropic":
            try:
                self.wall.check()
            except ValueError as exc:
                raise ConfigError(f"laminate: {exc}") from None

    @property
    def wall(self):
        """The tape's wall (:class:`tapecoil.theory.laminate.Wall`): A, B, D, H from tape.E,
        tape.nu and tape.h, from the plies, or as given."""
        return self.laminate.wall(self.tape)

    def check_coiling(self) -> None:
        """Refuse a hub rotation the tape is too short for (part of :meth:`check`).

        Raises :class:`ConfigError` naming ``coiling.hub_angle`` when the hub angle exceeds
        :func:`tapecoil.theory.max_hub_angle`.
        """
        from tapecoil import theory  # lazy: a configuration loads without scipy

        tp, r_hub, coiling = self.tape, self.hub.radius, self.coiling
        largest = theory.max_hub_angle(tp.L, r_hub, tp.h)
        if coiling.hub_angle > largest:
            raise ConfigError(
                f"coiling.hub_angle = {coiling.hub_angle:g} rad is more than the tape can coil: "
                f"the whole tape (tape.L = {tp.L:g} m) is on the hub (hub.radius = {r_hub:g} m, "
                f"tape.h = {tp.h:g} m per turn) after {largest:.4g} rad ({largest / (2 * math.pi):.3g} "
                f"turns), the largest hub angle this tape allows"
            )

    def check_model(self) -> None:
        """Refuse what the hybrid model cannot do (part of :meth:`check`;
        :func:`tapecoil.config.model.check_model`)."""
        check_model(self)

    def coiling_warnings(self) -> list[str]:
        """What is likely to keep a coiling run from its goal: a message per finding, naming its key.

        Empty when nothing is. Today one finding: ``coiling.tension`` below
        :func:`tapecoil.theory.required_coiling_tension`, the pull the hub needs. Not part of
        :meth:`check`: the commands that coil (``tapecoil coil``, ``run``, the coil and run
        sweeps) warn of these just before they start; loading a configuration for anything else
        (a report, a plot, a tension study with its own pull) stays quiet.
        """
        from tapecoil import theory  # lazy: a configuration loads without scipy

        tp, r_hub, coiling = self.tape, self.hub.radius, self.coiling
        needed = theory.required_coiling_tension(self.wall.bending, tp.alpha, tp.R, r_hub, tp.h)
        # in the non-unique regime no law gives the tension (see required_coiling_tension)
        if needed is None or coiling.tension >= needed[0]:
            return []
        return [
            f"coiling.tension = {coiling.tension:g} N is below the {needed[0]:.3g} N the hub needs "
            f"({needed[1]} at the first turn's mid-surface radius hub.radius + tape.h/2 = "
            f"{r_hub + tp.h / 2:g} m): with too little pull the tape does not wrap onto the hub "
            f"and the coiling stalls (with no pull the benchmark tape stalls at 2.49 rad on the "
            f"coarse mesh)"
        ]
