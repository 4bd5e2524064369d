"""Shared test setup: the benchmark configuration and MPI-aware skipping."""

import pytest

from tapecoil.config import load_config


def _compile_forms_at_o1() -> None:
    """The suite compiles a few hundred distinct forms, and from a fresh clone (as in CI) their
    compilation is most of its time: at -O1 the C compiler takes about a tenth less over the
    suite, and the kernels run a few per cent slower, against DOLFINx's -O2. Only the tests
    compile so; a run of tapecoil keeps DOLFINx's options (and a user's own)."""
    try:
        import dolfinx.jit
    except ImportError:
        return
    options = dolfinx.jit.DOLFINX_DEFAULT_JIT_OPTIONS
    _, text = options["cffi_extra_compile_args"]
    options["cffi_extra_compile_args"] = (["-O1", "-g0"], text)


_compile_forms_at_o1()


def _world_size() -> int:
    try:
        from mpi4py import MPI
    except ImportError:
        return 1
    return MPI.COMM_WORLD.size


def pytest_collection_modifyitems(config, items):
    # Tests marked mpi compare ranks; alone on one rank they would prove nothing.
    if _world_size() > 1:
        return
    skip = pytest.mark.skip(reason="mpi test: run under mpirun -n 2 (make test does)")
    for item in items:
        if "mpi" in item.keywords:
            item.add_marker(skip)


@pytest.fixture
def cfg():
    """The benchmark tape of the physics brief (the configuration defaults)."""
    return load_config()


@pytest.fixture
def coil_last_row():
    """A function: flatten a configuration's tape and coil it by ``angle`` on ``comm``; returns
    the last history row (for comparing a run on several ranks with one on each rank alone)."""

    def run(config, comm, angle):
        from tapecoil.phases.coiling import CoilingProblem
        from tapecoil.phases.coiling_run import CoilingRun

        model = CoilingProblem(config, comm)
        coiling = CoilingRun(model)
        coiling.flatten()
        coiling.coil(angle)
        return coiling.result.history[-1]

    return run
