"""A shell and a beam joined end to end and solved as one (:class:`HybridProblem`): the shell
where the section deforms, the beam where it keeps its shape.

Each part is stated as its own benchmark is (a :class:`~tapecoil.models.problem.ShellProblem`
and a :class:`~tapecoil.models.beam_problem.BeamProblem`: supports, loads, contact); the shell's
edge ``xi1_max`` is tied to a beam node as a rigid section
(:class:`~tapecoil.models.interface.RigidSectionTie`), or both its edges to the beam's pieces on
either side of the window, and one Newton solve
(:class:`~tapecoil.core.coupled_newton.CoupledSNESSolver`) steps the load parameter shared by
both::

    shell = ShellProblem(StripGeometry(R, b, window), resolution, material, director_frame="global")
    shell.clamp("xi1_min")
    beam = BeamProblem(line, length - window, elements, BeamSection.circular_arc(...), frame)
    beam.end_load(tip, force=(0, 0, 1))
    hybrid = HybridProblem(shell, beam, beam_end=start_of_beam, modulus=E)
    hybrid.solve(P, first_step=P / 4, max_step=P)
"""

from __future__ import annotations

import time

import numpy as np

from tapecoil.config import SolverConfig
from tapecoil.core.cell_state import gather_fields, scatter_fields
from tapecoil.core.coupled_newton import Block, CoupledSNESSolver, CouplingGroup, JointState
from tapecoil.core.dofs import global_scalar
from tapecoil.core.stepping import Continuation, Relaxation, StepRecord
from tapecoil.models.interface import RigidSectionTie

__all__ = ["HybridProblem"]


class HybridProblem:
    """The shell problem ``shell`` tied to the beam problem ``beam``: its edge ``xi1_max`` to the
    beam's node ``beam_end`` [m], or, with ``ties``, each edge named to a node, as a section of
    the shape given (``[(edge, node, section), ...]``, edge ``"xi1_min"`` or ``"xi1_max"``,
    section ``"arc"`` or ``"flat"``: a window of shell between two pieces of beam), with penalty
    factor ``penalty`` (:class:`RigidSectionTie`) and the wall's in-plane modulus ``modulus``
    [Pa]. ``name``: the PETSc options prefix is ``name + "_"``. ``contact``: a contact between
    the parts' surfaces (anything with ``term(numbering, weight, previous)``, its solver term
    in the joint solve, and ``accept()``, after each converged step: a
    :class:`~tapecoil.phases.turn_contact.TurnContact` on the shell's and the beam's joined
    surface), or None."""

    def __init__(
        self,
        shell,
        beam,
        beam_end=None,
        *,
        ties=None,
        modulus: float,
        penalty: float = 1e3,
        name: str = "hybrid",
        contact=None,
    ):
        if (beam_end is None) == (ties is None):
            raise ValueError("hybrid: give either beam_end or ties")
        if ties is None:
            ties = [("xi1_max", beam_end, "arc")]
        self.shell, self.beam, self.name = shell, beam, name
        self.contact = contact
        (x0, x1), _ = shell.surface.xi_range
        first, last = shell.strip.resolution.element_lengths(x1 - x0)
        element_lengths = {"xi1_min": first, "xi1_max": last}
        self.ties: dict[str, RigidSectionTie] = {}
        for edge, node, section in ties:
            if edge not in element_lengths or edge in self.ties:
                raise ValueError(f"hybrid: a tie's edge must be xi1_min or xi1_max, once each; got {edge!r}")
            self.ties[edge] = RigidSectionTie(
                shell.model,
                shell.edge(edge),
                beam.model,
                node,
                element_length=element_lengths[edge],
                modulus=modulus,
                penalty=penalty,
                section=section,
            )
        self.coupling = CouplingGroup([tie.coupling for tie in self.ties.values()])
        self._flattening: list[RigidSectionTie] = []
        self.tie_element = min(element_lengths[edge] for edge in self.ties)
        self.history: list[StepRecord] = []
        self.wall_time = 0.0

    def energy(self) -> float:
        """The strain energy of shell and beam and the ties' [J] (collective)."""
        comm = self.shell.strip.mesh.comm
        return (
            global_scalar(self.shell.model.strain_energy, comm)
            + self.beam.model.strain_energy()
            + self.coupling.energy()
        )

    # -- restart -------------------------------------------------------------------------------
    def _parts(self) -> dict:
        return {"shell": self.shell, "beam": self.beam, **{f"tie_{e}": tie for e, tie in self.ties.items()}}

    def state_tables(self) -> dict[str, np.ndarray]:
        """The state an accepted step leaves, shell, beam and ties, as tables that a hybrid of the
        same tape and window built again on any number of ranks takes back (:meth:`set_state`;
        :mod:`tapecoil.core.cell_state`): rank 0's hold it all, the others' are empty
        (collective)."""
        fields = {
            f"field:{p}:{n}": field
            for p, part in self._parts().items()
            for n, field in part.state_fields().items()
        }
        tables = gather_fields(fields, self.shell.strip.mesh.comm)
        for p, part in self._parts().items():
            for n, value in part.state_values().items():
                tables[f"value:{p}:{n}"] = np.asarray(value, dtype=float)
        return tables if self.shell.strip.mesh.comm.rank == 0 else {}

    def set_state(self, tables: dict[str, np.ndarray]) -> None:
        """Take the state of :meth:`state_tables` (every rank holding all of them; rank-local)."""
        for p, part in self._parts().items():
            fields = {f"field:{p}:{n}": field for n, field in part.state_fields().items()}
            scatter_fields(fields, tables)
            prefix = f"value:{p}:"
            part.set_state_values({k[len(prefix) :]: v for k, v in tables.items() if k.startswith(prefix)})
        self.set_load(self.beam.committed_load)
        self.state_changed()

    def state_changed(self) -> None:
        """The state was set from outside a solve (carried over, restored, settled): the parts'
        contact reads it as the converged one it measures the next steps from (collective)."""
        if self.contact is not None:
            self.contact.accept()

    def flatten(self, edge: str) -> None:
        """Flatten the flat tie at ``edge`` with the load parameter: its section goes from the arc
        at 0 to the flat strip at 1 (through the arcs of curvature (1 - f)/R), flat beyond; the
        beam's natural curvatures (a flattened strip's) grow with it."""
        tie = self.ties.get(edge)
        if tie is None or tie.section != "flat":
            raise ValueError(f"hybrid: flatten needs a flat tie at {edge!r}")
        self._flattening.append(tie)
        self._set_flatness(self.beam.committed_load)

    def _set_flatness(self, value: float) -> None:
        f = min(max(value, 0.0), 1.0)
        for tie in self._flattening:
            tie.flatness.value = f
        self.beam.model.natural_share.value = f

    def set_load(self, value: float) -> None:
        """The load parameter of the shell's and the beam's problems, and the ties' flatness while
        they flatten, in place."""
        self.shell.set_load(value)
        self.beam.set_load(value)
        if self._flattening:
            self._set_flatness(value)

    def commit(self) -> None:
        """Accept the joint state in place as a converged step: the ties', the beam's, the
        shell's and the contact's references move on."""
        for tie in self.ties.values():
            tie.commit()  # reads its end's rotation increment before the beam sets it to zero
        self.beam.commit()
        self.shell.commit(self.beam.committed_load)
        if self.contact is not None:
            self.contact.accept()

    def predict(self, load_from: float, load_to: float) -> None:
        """The initial guess of a step from ``load_from`` to ``load_to``: the beam's and the shell's."""
        self.beam.predict(load_from, load_to)
        self.shell.predict(load_from, load_to)

    def _solver(
        self,
        F_s,
        J_s,
        settings: SolverConfig,
        options: dict | None,
        beam_forms: tuple | None = None,
        contact_levels=(1.0, None),
    ) -> CoupledSNESSolver:
        """The joint Newton solver of the shell's forms ``F_s``, ``J_s`` and the beam's (its
        energy's, or ``beam_forms``: its equation of motion, say), with the parts' contact if
        any: its force at ``contact_levels`` = (weight, (weight_old, the old states' Functions)
        or None), generalized-alpha's average in time."""
        beam_forms = beam_forms or self.beam.forms()
        blocks = [
            Block(F, J, part.model.q, part.bcs, part.point_forces, part.model.rounding_scale())
            for part, (F, J) in ((self.shell, (F_s, J_s)), (self.beam, beam_forms))
        ]
        solver = CoupledSNESSolver(
            blocks,
            self.coupling,
            prefix=f"{self.name}_",
            options={**settings.petsc_options, **(options or {})},
            rtol=settings.rtol,
            atol=settings.atol,
            max_it=settings.max_newton,
        )
        if self.contact is not None:
            solver.terms.append(self.contact.term(solver.numbering(), *contact_levels))
        return solver

    def solve(
        self,
        load: float,
        *,
        first_step: float,
        max_step: float,
        min_step: float | None = None,
        max_cutbacks: int = 8,
        relaxation: float | None = None,
        on_step=None,
        solver_config: SolverConfig | None = None,
        options: dict | None = None,
        easy_iterations: int = 5,
    ) -> list[StepRecord]:
        """Step the load parameter from where it is to ``load`` (adaptive, with cut-back), steps
        in the parameter's units, grown after steps of at most ``easy_iterations`` Newton
        iterations; raises :class:`~tapecoil.core.stepping.ContinuationError` with
        the last converged state kept when no step converges.

        ``relaxation``: the starting viscosity [N/m^3] of pseudo-transient relaxation on the
        shell (:meth:`NaghdiShell.relaxation`, its length scale the shell's element), tried once
        ``max_cutbacks`` cut-backs have not passed a snap; None: none."""
        start = self.beam.committed_load
        span = load - start
        if span == 0 or not (0 < first_step <= max_step and first_step <= abs(span)):
            raise ValueError(
                f"hybrid solve: steps must satisfy 0 < first_step ({first_step}) <= max_step "
                f"({max_step}) and first_step <= |load - start| ({abs(span)})"
            )
        settings = solver_config or SolverConfig()
        F_s, J_s = self.shell.forms()
        relax = None
        if relaxation is not None:
            coefficient, previous, viscous = self.shell.model.relaxation(length_scale=self.tie_element)
            F_s = F_s + viscous
            J_s = self.shell.model.jacobian_form(F_s)
            relax = Relaxation(coefficient, previous, scale=relaxation, state=self.shell.model.q)
        solver = self._solver(F_s, J_s, settings, options)
        smallest = 1e-6 * abs(span) if min_step is None else min_step
        control = settings.control(
            initial_step=first_step / abs(span),
            max_step=max_step / abs(span),
            min_step=smallest / abs(span),
            max_cutbacks=max_cutbacks,
        )
        continuation = Continuation(
            solve=solver.solve,
            set_load=self.set_load,
            state=JointState(self.shell.model.q, self.beam.model.q),
            control=control,
            relaxation=relax,
            commit=self.commit,
            on_step=on_step,
            predict=self.predict,
            easy_iterations=easy_iterations,
        )
        t0 = time.perf_counter()
        try:
            self.history += continuation.run(start, load)
        finally:
            self.wall_time = time.perf_counter() - t0
            self.timings = dict(solver.timings)
            solver.destroy()
        return self.history
