"""Verification cases of the shell core, the beam and the hybrid, each returning computed values
against references.

The CLI (``tapecoil verify``) and the tests run the same functions.
"""

from __future__ import annotations

from mpi4py import MPI

from tapecoil.config import Config
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.verification import CASES
from tapecoil.verification.beam import (
    BEAM_MESHES,
    BEND_MESHES,
    HUB_MESHES,
    TURNS_MESHES,
    beam_bend45,
    beam_hub,
    beam_rollup,
    beam_turns,
)
from tapecoil.verification.capstan import capstan_grid
from tapecoil.verification.checks import CaseResult
from tapecoil.verification.hybrid import CANTILEVER_LENGTH, hybrid_cantilever, hybrid_fold, hybrid_window
from tapecoil.verification.hybrid_coil import hybrid_coil
from tapecoil.verification.hybrid_deploy import hybrid_deploy
from tapecoil.verification.hybrid_motion import hybrid_vibration
from tapecoil.verification.moment_rotation import tape_moment_rotation
from tapecoil.verification.roof import ROOF_MESHES, roof
from tapecoil.verification.sze import (
    CANTILEVER_MESHES,
    ROLLUP_MESHES,
    SEMICYLINDER_MESHES,
    SLIT_PLATE_MESHES,
    cantilever_shear,
    rollup,
    semicylinder,
    slit_plate,
)
from tapecoil.verification.tape import stress_free, tape_fold, tape_linear

# the mesh preset of a case when none is asked for: the coarsest that passes. The tape fold's
# radius R = 15 mm needs the default 4 mm elements: on the coarse 12.5 mm ones the fold's
# energy density misses mu by more than the 5 % tolerance
DEFAULT_PRESETS = {"tape-fold": "default"}


def run_case(name: str, config: Config, preset: str | None = None, comm=MPI.COMM_WORLD) -> CaseResult:
    """Run the verification case ``name`` on the mesh preset ``preset`` (collective).

    ``preset`` None: the case's own default (:data:`DEFAULT_PRESETS`, else coarse). The tape
    cases take the tape of ``config``, and every case with a solve its ``[solver]`` settings.
    """
    from tapecoil.config import MeshConfig

    if name not in CASES:
        raise ValueError(f"unknown verification case {name!r} (known: {', '.join(CASES)})")
    preset = preset or DEFAULT_PRESETS.get(name, "coarse")
    tape_res = MeshResolution.from_config(MeshConfig(preset=preset), config.tape.L)
    if name == "stress-free":
        result = stress_free(config, tape_res, comm)
    elif name == "tape-linear":
        result = tape_linear(config, tape_res, comm=comm)
    elif name == "rollup":
        result = rollup(ROLLUP_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "cantilever-shear":
        result = cantilever_shear(CANTILEVER_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "semicylinder":
        result = semicylinder(SEMICYLINDER_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "slit-plate":
        result = slit_plate(SLIT_PLATE_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "roof-snap-through":
        result = roof(12.7, ROOF_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "roof-snap-back":
        result = roof(6.35, ROOF_MESHES[preset], comm=comm, solver_config=config.solver)
    elif name == "capstan":
        result = capstan_grid(comm, solver_config=config.solver)  # on meshes of its own
    elif name == "tape-moment-rotation":
        result = tape_moment_rotation(config, preset, comm)  # on meshes of its own (FOLD_MESHES)
    elif name == "beam-rollup":
        result = beam_rollup(BEAM_MESHES[preset], comm=comm)
    elif name == "beam-bend45":
        result = beam_bend45(BEND_MESHES[preset], comm=comm)
    elif name == "beam-hub":
        result = beam_hub(HUB_MESHES[preset], comm=comm)
    elif name == "beam-turns":
        result = beam_turns(TURNS_MESHES[preset], comm=comm)
    elif name == "hybrid-cantilever":
        resolution = MeshResolution.from_config(MeshConfig(preset=preset), CANTILEVER_LENGTH)
        result = hybrid_cantilever(config, resolution, comm=comm)
    elif name == "hybrid-fold":
        result = hybrid_fold(config, tape_res, comm=comm)
    elif name == "hybrid-window":
        result = hybrid_window(config, comm=comm)  # on meshes of its own, whatever the preset
    elif name == "hybrid-coil":
        result = hybrid_coil(config, preset, comm=comm)
    elif name == "hybrid-deploy":
        result = hybrid_deploy(config, preset, comm=comm)
    elif name == "hybrid-vibration":
        resolution = MeshResolution.from_config(MeshConfig(preset=preset), CANTILEVER_LENGTH)
        result = hybrid_vibration(config, resolution, comm=comm)
    else:
        result = tape_fold(config, tape_res, comm=comm)
    result.info.setdefault("preset", preset)  # a case on meshes of its own names them
    return result
