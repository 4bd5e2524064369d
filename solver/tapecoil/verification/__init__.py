"""Verification of the shell core and the beam against exact and published results (:mod:`.cases`).

The case names live here, apart from the cases, so that the command line can offer them as
choices without loading DOLFINx: ``tapecoil theory`` and ``tapecoil config`` need none of it.
"""

CASES = (
    "stress-free",
    "tape-linear",
    "rollup",
    "cantilever-shear",
    "semicylinder",
    "slit-plate",
    "tape-fold",
    "beam-rollup",
    "beam-bend45",
    "beam-hub",
    "beam-turns",
    "hybrid-cantilever",
    "hybrid-fold",
    "hybrid-window",
    "hybrid-coil",
    "hybrid-vibration",
    "hybrid-deploy",
    "roof-snap-through",
    "roof-snap-back",
    "tape-moment-rotation",
    "capstan",
)


def not_applicable(name: str, config) -> str | None:
    """Why the case ``name`` cannot run on the tape of ``config`` (None: it can). The hybrid's
    beam takes an isotropic arc section; its coiling is the opposite sense's, on the spiral."""
    if name.startswith("hybrid-") and config.laminate.kind != "isotropic":
        return "the hybrid's beam takes an isotropic arc section, and this tape's wall is laminated"
    if name == "hybrid-coil" and config.coiling.sense != "opposite":
        return "the hybrid coils in the opposite sense only, and this tape is coiled in the equal sense"
    if name == "hybrid-coil" and config.contact.turns != "spiral":
        return "the hybrid's beam rests on the spiral of turns, and this run's turns touch by their surfaces"
    if name == "hybrid-deploy":
        from tapecoil.config.model import hybrid_need

        need = hybrid_need(config)
        return None if need is None else f"the hybrid coils and deploys only with {need}"
    return None
