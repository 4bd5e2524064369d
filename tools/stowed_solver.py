"""The coiling solver of a stowed checkpoint, its Newton matrix assembled at the checkpoint's state.

Shared by the tools that study that matrix (tools/factorisation.py, tools/contact_preconditioner.py).
"""

from pathlib import Path

from tapecoil.config import load_config
from tapecoil.phases.coiling import read_checkpoint


def stowed_solver(stowed: Path, comm, operator: bool = False):
    """(model, solver) of the coiling checkpoint ``stowed`` (a results directory's stowed/, any
    rank count), with the solver's matrix A assembled at the checkpoint's state and, with
    ``operator``, its Newton operator (A and the terms' applied part) set up."""
    config = load_config(Path(stowed).parent / "config.toml")
    model, _meta = read_checkpoint(stowed, config, comm)
    solver = model.solver
    for term in solver.terms:
        term.begin()
    # the solver assembles at its vector x: the checkpoint's state, not the zero it starts as
    model.model.q.x.petsc_vec.copy(solver.x)
    if operator:
        solver._use_operator()
    solver._jacobian(None, solver.x, solver.A, solver.A)
    return model, solver
