"""Which model wrote a checkpoint or a phase's summary: the tag under ``"model"`` in a
checkpoint's restart state and in a summary's run figures.

The hybrid writes :data:`HYBRID`; the full shell writes no tag (its checkpoints predate the
hybrid, and old ones must still restore), so a state without one is the full shell's.
"""

from __future__ import annotations

KEY = "model"
HYBRID = "hybrid"


def by_hybrid(state: dict) -> bool:
    """Whether ``state`` (a restart state or a summary's run figures) was written by the hybrid."""
    return state.get(KEY) == HYBRID
