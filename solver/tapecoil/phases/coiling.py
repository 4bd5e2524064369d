"""Quasi-static coiling of a tape spring onto a rotating hub, as in the thesis's benchmark run.

The procedure mirrors the physical one (the thesis's benchmark run, physics brief Sec. 1):

1. Flattening: the root edge, attached to the hub, is driven from the tape's curved section to
   the flat section on the hub's top generator (curvature (1 - f)/R, f from 0 to 1) while the
   pull at the free end rises to T. The section near the root flattens onto the hub instead of
   snapping at the first rotation.
2. Coiling: the hub turns (load-stepped hub angle, adaptive steps with cut-back); the root
   turns with it (displacement and director), the tape wraps onto the hub and then onto its own
   turns (penalty contact, :mod:`tapecoil.hub.contact`), and the free end slides along the guide
   line tangent to the hub's top (z = 0: displacement across and normal to the line and the end's
   rotations held), pulled by T along +x.

Each step starts from a predictor: material already on the coil turns rigidly with the hub; the
rest (ploy region and free part) takes the state of the material that was a wound length
ds = r dtheta further back along the tape (the "shift": steady coiling looks the same in the lab
frame from step to step), or, on meshes too coarse to interpolate along the tape, the secant
extrapolation of the last two converged states (:mod:`tapecoil.phases.predictors`).

All quantities are SI. Sign conventions: the hub angle is positive in the coiling sense (the root
moves from the generator it touches towards -x; :class:`~tapecoil.hub.frame.HubFrame` places and
turns the hub for either coiling sense); in opposite-sense coiling the longitudinal curvature of
the coil is negative in the shell's convention (opposite to the section's +1/R), in equal-sense
coiling positive. The measures report it as a magnitude.
"""

from __future__ import annotations

import math
from pathlib import Path

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from tapecoil import theory
from tapecoil.config import Config, ConfigError
from tapecoil.core import checkpoint, jit
from tapecoil.core.checkpoint import state_parts
from tapecoil.core.dofs import global_scalar, owned_constrained_dofs
from tapecoil.core.newton import SNESSolver
from tapecoil.geometry.meshes import FREE_END, MeshResolution
from tapecoil.models.edges import facet_condition
from tapecoil.phases.predictors import CoilingPredictor, choose_predictor
from tapecoil.phases.tape_on_hub import TapeOnHub

# the free end's guide, the full shell's and the hybrid window's: its displacement across and
# normal to the guide line (the hub's top tangent) and its rotations held, so that the pull
# draws it along the line
GUIDE_COMPONENTS = ((0, 1), (0, 2), (1,))

# The free part a coiling needs at its end (:func:`free_end_room`), in elements at the free end
# and in lengths of the guide line inside the coil: the smallest that the coarse and the default
# meshes coil through, measured (docs/notes/coiling.md, *Room for the free end*)
_ROOM_ELEMENTS = 2.4
_ROOM_INSIDE = 2.7


def free_end_room(config: Config) -> tuple[float, float, float]:
    """The free length [m] a coiling to ``coiling.hub_angle`` leaves, and the least it needs: on
    account of the coil's thickness, and of the mesh.

    The free end slides along the guide line tangent to the hub, its section held in the shape
    it has. The coil's outer turn stands t_c = h theta / (2 pi) above the hub, so the line runs
    inside the coil for x_c = sqrt((r_hub + t_c)^2 - r_hub^2) from where it touches the hub: the
    tape between the coil and its end must bend down onto the line and stay off the coil, and
    the elements at the end must resolve that bend. A free part shorter than
    ``_ROOM_INSIDE`` x_c or ``_ROOM_ELEMENTS`` free-end elements presses the tape through its
    outer turn before the hub angle is reached.
    """
    tp, r_hub, theta = config.tape, config.hub.radius, config.coiling.hub_angle
    free = tp.L - theory.coiled_length_from_rotation(theta, r_hub, tp.h)
    thickness = tp.h * theta / (2 * math.pi)
    inside = math.sqrt((r_hub + thickness) ** 2 - r_hub**2)
    element = MeshResolution.from_config(config.mesh, tp.L).element_lengths(tp.L)[1]
    return free, _ROOM_INSIDE * inside, _ROOM_ELEMENTS * element


def check_free_end_room(config: Config) -> None:
    """Refuse, before computing, a hub angle that leaves the free end too little room
    (:func:`free_end_room`): a :class:`ConfigError` naming ``coiling.hub_angle``, the room left
    and the room needed."""
    free, for_coil, for_mesh = free_end_room(config)
    if free >= max(for_coil, for_mesh):
        return
    if for_mesh > for_coil:
        need = (
            f"{for_mesh * 1e3:.1f} mm on this mesh ({_ROOM_ELEMENTS:g} elements at the free end; a finer "
            f"mesh.element_size needs less, down to {for_coil * 1e3:.1f} mm)"
        )
    else:
        need = f"{for_coil * 1e3:.1f} mm to bend from the coil's outer turn down onto the guide line"
    raise ConfigError(
        f"coiling.hub_angle = {config.coiling.hub_angle:g} rad leaves {free * 1e3:.1f} mm of the tape "
        f"free, and its end on the guide line needs {need}: the free part would be pressed through "
        "the coil's outer turn before the hub angle is reached (a smaller hub angle or a longer tape)"
    )


class CoilingProblem:
    """A coiling run's loads and solver on a :class:`TapeOnHub`: the guide, the pull, the
    relaxation, the SNES and the predictor.

    ``tape``: an existing tape on its hub (a checkpoint's); otherwise one is built from
    ``config`` (or ``resolution``). The free end is pulled by the force T (``coiling.tension``).
    ``obstacles``: further rigid bodies turned with the hub, each with a penalty ``energy`` (UFL)
    and ``turn(hub_angle)`` (the temporary cylinders of tools/seeded_wrap_study.py).
    """

    def __init__(
        self,
        config: Config,
        comm=MPI.COMM_WORLD,
        resolution: MeshResolution | None = None,
        tape: TapeOnHub | None = None,
        obstacles: tuple = (),
    ):
        self.config = config
        self.comm = comm
        self.tape = tape = tape or TapeOnHub(config, comm, resolution)
        tp = config.tape
        # the parts of the tape this phase loads and solves for
        self.strip, self.model, self.frame, self.root, self.contact = (
            tape.strip,
            tape.model,
            tape.frame,
            tape.root,
            tape.contact,
        )
        self.element_length, self.penalty = tape.element_length, tape.penalty
        strip, model = self.strip, self.model

        free_end = strip.facet_tags.find(FREE_END)
        self.guide = [facet_condition(model, sub, free_end) for sub in GUIDE_COMPONENTS]
        bcs = self.root.bcs + [bc for _, bc in self.guide]
        self.tension = dolfinx.fem.Constant(strip.mesh, 0.0)
        self.bcs = bcs

        # the pull: T spread evenly over the free end's arc; its work is T times the end's mean u_x
        self.end_slide_form = jit.form(model.u[0] / tp.b * model.ds(FREE_END))
        self.pull_work = self.tension * model.u[0] / tp.b * model.ds(FREE_END)
        self.obstacles = tuple(obstacles)
        self.energy = tape.energy + sum(o.energy for o in self.obstacles)
        self.viscosity, self.previous, viscous = model.relaxation(length_scale=self.element_length)
        potential = self.energy - self.pull_work
        self.residual_form = ufl.derivative(potential, model.q, model.dq)
        friction = tape.friction_residual()
        if friction is not None:
            self.residual_form = self.residual_form + friction
        F = self.residual_form + viscous
        # without friction the Jacobian is the Hessian of a potential (the pull is a dead load,
        # contact a penalty energy, the relaxation a symmetric viscosity) and the boundary
        # conditions keep it symmetric: MUMPS LDL^T instead of LU, a faster factorisation with
        # the same results (the tape's solver options ask for LU where it is not)
        self.solver = SNESSolver.from_config(
            F,
            model.jacobian_form(F),
            model.q,
            bcs,
            config.solver,
            prefix="coil_",
            defaults={"pc_type": "cholesky", **tape.solver_options()},
            options=config.coiling.petsc_options,
            state_scale=model.rounding_scale(),
        )
        self.solver.terms += tape.contact_terms(model.q, bcs)
        self._end_dofs = tape.edge_dofs(FREE_END, (0, 0))
        self.predictor = choose_predictor(config.coiling.predictor, self.element_length, tape.r_hub)
        self.predictions = CoilingPredictor(tape, self.predictor, comm)

    # -- loading --------------------------------------------------------------------------
    def set_flattening(self, f: float) -> None:
        self.root.set(f, 0.0)
        self._turn_hub(0.0)
        self.tension.value = f * self.config.coiling.tension

    def set_hub_angle(self, angle: float) -> None:
        self.root.set(1.0, angle)
        self._turn_hub(angle)

    def _turn_hub(self, angle: float) -> None:
        self.contact.turn(angle)
        for obstacle in self.obstacles:
            obstacle.turn(angle)

    def predict(self, angle_from: float, angle_to: float) -> None:
        """The state's initial guess at ``angle_to`` (:class:`CoilingPredictor`)."""
        self.predictions.predict(self.model.q.x.array, angle_from, angle_to)

    def update(self, angle: float) -> None:
        """After a converged step: winding angles and the turns' sides from the new state; the
        predictor remembers it."""
        self.contact.update(angle)
        self.tape.accept_state()
        self.predictions.remember(angle, self.model.q.x.array)

    def end_slide(self) -> float:
        """Mean displacement of the free end along the guide (+x) [m]."""
        return global_scalar(self.end_slide_form, self.model.mesh.comm)

    def internal_force(self) -> np.ndarray:
        """The internal force vector dE/dq (strain, the hub's and the turns' contact, the
        obstacles), local array (collective)."""
        return self.tape.internal_force(self.energy)

    def hub_torque(self, internal_force: np.ndarray | None = None, eps: float = 1e-6) -> float:
        """The torque the tape exerts on the hub through the root's reactions [N m] (collective).

        The reaction on each attached dof times the rate at which the hub's turning moves it,
        d q_root / d hub angle (central differences of the attachment), summed: the virtual
        work of the reactions in a turn of the hub; plus, with friction on the hub, the torque
        of its traction (:meth:`~tapecoil.hub.friction.HubFriction.hub_torque`). The hub's
        pressure passes through the axis and adds none. Independent of the energy balance of
        the steps (the history's hub_torque).
        """
        f = self.internal_force() if internal_force is None else internal_force
        angle = self.root.angle
        shifted = []
        for sign in (1.0, -1.0):
            self.root.set(1.0, angle + sign * eps)
            values = np.zeros_like(f)
            for bc in self.root.bcs:
                bc.set(values)
            shifted.append(values)
        self.root.set(1.0, angle)
        dofs = owned_constrained_dofs(self.model.W, self.root.bcs)
        rate = (shifted[0][dofs] - shifted[1][dofs]) / (2 * eps)
        root = float(self.comm.allreduce(float(np.dot(f[dofs], rate)), op=MPI.SUM))
        return root + (self.tape.friction.hub_torque() if self.tape.friction is not None else 0.0)

    def edge_forces(self, internal_force: np.ndarray | None = None) -> dict[str, float]:
        """Forces at the two ends from one assembly of the internal force [N] (collective).

        ``internal_force``: :meth:`internal_force` at the current state, if the caller has it.

        ``tension``: the internal force along +x on the free end, what the pull holds.
        ``root_tension``: the axial force N the tape carries into the root attachment (tension
        positive), the internal force on the root edge along the tape's direction there, turned
        with the hub (:meth:`HubFrame.tangent`). With frictionless contact, N + M kappa - U is the same all
        along the tape (the configurational force balance of physics.md Sec. 5), so T - N is the
        coiling tension M kappa - U of the first turn: Eq. 2.6 for a flattened coil.
        """
        f = self.internal_force() if internal_force is None else internal_force
        root = float(self.frame.tangent(self.root.angle) @ self.tape.root_force(f))
        end = self.comm.allreduce(float(f[self._end_dofs].sum()), op=MPI.SUM)
        return {"tension": float(end), "root_tension": -root}


# -- checkpoint -------------------------------------------------------------------------------
def write_checkpoint(model: CoilingProblem, path: str | Path, meta: dict, tables: dict | None = None) -> None:
    """The state a restart or the deployment needs (:meth:`TapeOnHub.write_checkpoint`), with,
    for the secant predictor, the previous converged state; ``meta`` holds the hub angle, the
    tension and the stepping's restart state; ``tables``: another model's state beside it (the
    hybrid's)."""
    extra = {}
    previous = model.predictions.previous_converged()
    if previous is not None:
        state = dolfinx.fem.Function(model.model.W)
        state.x.array[:] = previous[1]
        extra = state_parts(state, "previous_")
    model.tape.write_checkpoint(path, meta, extra, tables)


def read_checkpoint(path: str | Path, config: Config, comm=MPI.COMM_WORLD) -> tuple[CoilingProblem, dict]:
    """A :class:`CoilingProblem` in the state of a checkpoint (any phase's, any rank count)."""
    tape, meta = TapeOnHub.read_checkpoint(path, config, comm)
    model = CoilingProblem(config, comm, tape=tape)
    previous_angle = meta.get("run", {}).get("previous_angle")
    if previous_angle is not None:
        previous = checkpoint.empty_state_parts(model.model.W, "previous_")
        checkpoint.read_functions(path, previous)
        state = dolfinx.fem.Function(model.model.W)
        checkpoint.set_state(state, previous, "previous_")
        model.predictions.set_previous_converged(previous_angle, state.x.array)
    model.tension.value = meta["tension"]
    return model, meta
