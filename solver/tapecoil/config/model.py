"""The [model] table: the tape's structural model, and what the hybrid needs of the other
tables."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from tapecoil.config.params import POSITIVE, ConfigError, param


@dataclass
class ModelConfig:
    """The tape's structural model in coiling and deployment.

    Attributes:
        kind: 'shell' (the Naghdi shell over the whole tape) or 'hybrid' (shell on a window
            around the ploy region, geometrically exact beams before and after it:
            docs/notes/hybrid.md). The hybrid coils in the opposite sense on the spiral of turns
            (contact.turns = 'spiral'), on an ungraded mesh (mesh.grading = 1). Its coiled state
            is carried into the full shell and settled there by one solve at the final hub
            angle (the stowed state); the hybrid then deploys from its own coiled state, its
            window following the lift-off, by generalized-alpha (deployment.rho_inf < 1), the
            hub held or free (deployment.hub), or a driven hub pays it out (the payout, from
            the hybrid's own coil).
        window_ahead: the hybrid's shell beyond the lift-off point [m] (the ploy region and a
            margin: with 0.15 m the outer turn's coiling tension came out 0.7 % low on the 0.5 m
            benchmark and 1.4 % low on a 1 m tape, with 0.2 m within its error of the full
            shell's; docs/notes/hybrid.md, "The window's reach").
        window_behind: the hybrid's shell on the coil behind the lift-off point [m].
        window_move: how far the lift-off travels before the window moves with it [m].
        window_release: the coil the hybrid's window holds behind the lift-off when the tape is
            let go [m] (at least: more if the coiling's window held more; a coil shorter than
            this keeps the coiling's window). The release sends a wave of lift down the coil,
            on the benchmark above two thicknesses to about 0.1 m behind the lift-off with the
            default steps, which the flattened beam cannot follow (docs/notes/hybrid.md, "The
            release's wave and the window's length"). The window takes its own length again at
            its first move.
        tie_penalty: the penalty factor of the ties between shell and beams [-] (times the
            stiffness of one shell element).
        beam_contact: how the flattened beam rests on the turns: 'width' (across its flat
            section, as the shell: its edges and line by Simpson's rule) or 'line' (its
            centre line alone, which lets the section turn about it unresisted: the 2 m
            tape's coil then came loose a third of a second into its deployment;
            docs/notes/hybrid.md, "The flattened coil's twist").
    """

    kind: str = param("shell", "", ("shell", "hybrid"))
    window_ahead: float = param(0.2, "m", POSITIVE)
    window_behind: float = param(0.025, "m", POSITIVE)
    window_move: float = param(0.025, "m", POSITIVE)
    window_release: float = param(0.15, "m", POSITIVE)
    tie_penalty: float = param(1e2, "-", POSITIVE)
    beam_contact: str = param("width", "", ("line", "width"))


def check_model(config) -> None:
    """Refuse what the hybrid model cannot do in ``config`` (a :class:`~tapecoil.config.Config`),
    naming the key to change, and the window's settings on the shell model, where they would
    not act."""
    model = config.model
    if model.kind == "shell":
        defaults = ModelConfig()
        for f in dataclasses.fields(model):
            if f.name != "kind" and getattr(model, f.name) != getattr(defaults, f.name):
                raise ConfigError(
                    f"model.{f.name} acts only on the hybrid model: set model.kind = 'hybrid', or "
                    f"leave model.{f.name} out"
                )
        return
    need = hybrid_need(config)
    if need is not None:
        raise ConfigError(f"model.kind = 'hybrid' needs {need}")
    if config.solver.stability:
        raise ConfigError(
            "solver.stability = true judges the shell model's coiling and payout, not the hybrid's: set "
            "model.kind = 'shell', or leave solver.stability out"
        )
    window = model.window_ahead + model.window_behind
    if window >= config.tape.L:
        raise ConfigError(
            f"model.window_ahead + model.window_behind = {window:g} m must be shorter than the tape "
            f"(tape.L = {config.tape.L:g} m): the hybrid's shell is a window of it"
        )


def _coiling_needs(config) -> tuple:
    """What the hybrid needs to coil the tape of ``config``: (met, "key = value", why) each."""
    return (
        (
            config.coiling.sense == "opposite",
            "coiling.sense = 'opposite'",
            "the hybrid coils in that sense only",
        ),
        (
            config.mesh.grading == 1.0,
            "mesh.grading = 1",
            "its shell and beams share their nodes along the tape",
        ),
        (
            config.contact.hub_friction == 0.0,
            "contact.hub_friction = 0",
            "its window and beams rest on the hub without friction",
        ),
    )


def _first_unmet(needs) -> str | None:
    return next((f"{setting}: {why}" for ok, setting, why in needs if not ok), None)


def hybrid_coiling_need(config) -> str | None:
    """The first setting the hybrid needs to coil the tape of ``config`` and does not have, with
    the reason ("key = value: why"), or None."""
    return _first_unmet(_coiling_needs(config))


def hybrid_need(config) -> str | None:
    """The first setting the hybrid needs to coil and deploy the tape of ``config`` and does not
    have, with the reason ("key = value: why"), or None."""
    deploying = (
        config.deployment.rho_inf < 1.0,
        "deployment.rho_inf < 1",
        "it deploys by generalized-alpha (the energy-conserving scheme is the full shell's)",
    )
    return _first_unmet((*_coiling_needs(config), deploying))


def frictionless_need(config, phases) -> str | None:
    """Why ``phases`` (names: "coiling", "deployment", "payout") cannot run the tape of
    ``config`` as configured, or None: the hub's friction acts in the coiling and in a
    deployment with the hub held."""
    mu = config.contact.hub_friction
    if mu == 0.0:
        return None
    if "payout" in phases:
        return (
            f"contact.hub_friction = {mu:g} acts in the coiling and in a deployment with the hub held; "
            "the payout takes the hub frictionless: set contact.hub_friction = 0 for it"
        )
    if "deployment" in phases and config.deployment.hub == "free":
        return (
            f"contact.hub_friction = {mu:g} acts with the hub held; a hub free to turn "
            "(deployment.hub = 'free') takes it frictionless: set contact.hub_friction = 0, or "
            "deployment.hub = 'fixed'"
        )
    return None


def hybrid_deployment_need(config) -> str | None:
    """Why the hybrid cannot deploy the tape of ``config`` as it coils it, or None (also for the
    shell model). Its window leaves the root only once the coil is ``window_behind +
    window_move`` long, and at release it reaches the free end: where even the longest coil that
    ``coiling.hub_angle`` can wind (each turn a thickness further out than the hub) is shorter,
    the window holds the whole tape at release and nothing of it is beam."""
    tp, model = config.tape, config.model
    if model.kind != "hybrid":
        return None
    angle = config.coiling.hub_angle
    longest = angle * (config.hub.radius + tp.h * (1.0 + angle / (2.0 * math.pi)))
    least = model.window_behind + model.window_move
    if longest >= least:
        return None
    return (
        f"coiling.hub_angle = {angle:g} rad winds at most {longest:.4g} m of coil, less than the "
        f"model.window_behind + model.window_move = {least:g} m after which the hybrid's window "
        "leaves the root: at release the window would hold the whole tape, nothing of it beam. "
        "Coil further, or deploy this tape with model.kind = 'shell'"
    )
