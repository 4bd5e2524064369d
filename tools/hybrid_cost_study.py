"""The cost of the hybrid against the full shell as the tape grows: the benchmark tape folded by
its turned end to pi (`tapecoil verify hybrid-fold`: 0.3 m of shell at the root, the arc-section
beam beyond), at lengths LENGTHS [m], on the coarse mesh preset, one rank. Prints, per length,
the DOFs, Newton iterations and wall times of both models, their ratio and the hybrid's
plateau against the full shell's (docs/notes/hybrid.md, "Cost against length").

    tools/env.sh run env PYTHONPATH=solver python3 tools/hybrid_cost_study.py [PRESET [LENGTHS...]]
"""

import sys

from tapecoil.config import MeshConfig, config_from_dict
from tapecoil.geometry.meshes import MeshResolution
from tapecoil.verification.hybrid import hybrid_fold

preset = sys.argv[1] if len(sys.argv) > 1 else "coarse"
lengths = [float(v) for v in sys.argv[2:]] or [0.5, 1.0, 2.0]
print(
    "| L [m] | DOFs hybrid / shell | Newton its hybrid / shell | wall hybrid / shell [s] | ratio "
    "| plateau hybrid / shell |"
)
print("|---|---|---|---|---|---|")
for length in lengths:
    config = config_from_dict({"tape": {"L": length}})
    result = hybrid_fold(config, MeshResolution.from_config(MeshConfig(preset=preset), length))
    info = result.info
    wall = info["wall_time"]
    plateau = next(c for c in result.checks if c.name.startswith("moment plateau / the full"))
    print(
        f"| {length:g} | {info['dofs']['hybrid']:,} / {info['dofs']['full_shell']:,} "
        f"| {info['newton_iterations']['hybrid']:,} / {info['newton_iterations']['full_shell']:,} "
        f"| {wall['hybrid']:.1f} / {wall['full_shell']:.1f} | {wall['full_shell'] / wall['hybrid']:.2f} "
        f"| {plateau.computed:.4f} |",
        flush=True,
    )
