"""One measured quantity against its reference: what it is, where the reference comes from, and
the tolerance it is held to and why.

Runs (coiling, deployment) and verification cases produce measures; the summary, the command
line, the report and the plots consume them by their fields, so adding a measure means writing
it where it is measured and nowhere else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Measure:
    """A computed quantity against its reference.

    Attributes:
        label: what the quantity is, with its unit, for tables ("outer coil radius [m]").
        computed: the measured value; None when the run did not reach it.
        reference: the reference value (same unit).
        tolerance: the largest error that passes (relative, or absolute when ``absolute``);
            None: reported against the reference without a pass mark.
        source: where the reference comes from (an equation of the physics brief, a paper).
        basis: why the tolerance is what it is.
        absolute: the error is |computed - reference| instead of the relative error.
        bound: "lower": the reference is a bound the computed value must reach (a separation at
            least so large), not a value to match; the error is then the shortfall below it
            (zero when reached), in the quantity's unit, and the tolerance 0 (or None: a reading
            where the bound does not apply, reported without it).
        extra: further figures of the measurement (worst cell, sample counts, ...).
    """

    label: str
    computed: float | None
    reference: float
    tolerance: float | None = None
    source: str = ""
    basis: str = ""
    absolute: bool = False
    bound: str | None = None
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.bound not in (None, "lower"):
            raise ValueError(f"a measure's bound is None or 'lower', got {self.bound!r}")
        if self.bound is not None and self.tolerance not in (0.0, None):
            raise ValueError("a bound's tolerance is 0 (the computed value must reach it) or None")

    @property
    def error(self) -> float | None:
        """|computed - reference|, relative to |reference| unless ``absolute``; None if not reached."""
        if self.computed is None:
            return None
        if self.bound == "lower":
            return float(max(self.reference - self.computed, 0.0))
        difference = abs(self.computed - self.reference)
        if self.absolute:
            return float(difference)
        return float(difference / abs(self.reference)) if self.reference else math.nan

    @property
    def passed(self) -> bool | None:
        """Within tolerance (False when not reached or not finite); None without a tolerance."""
        if self.tolerance is None:
            return None
        error = self.error
        return bool(error is not None and math.isfinite(error) and error <= self.tolerance)

    def to_dict(self) -> dict:
        """The measure as JSON-ready data (summary.json)."""
        return {
            "computed": None if self.computed is None else float(self.computed),
            "reference": float(self.reference),
            "error": self.error,
            **self.extra,
            "label": self.label,
            "tolerance": self.tolerance,
            "absolute": self.absolute or self.bound is not None,
            "bound": self.bound,
            "passed": self.passed,
            "source": self.source,
            "basis": self.basis,
        }


def is_measure(entry) -> bool:
    """Whether a summary entry is a measure's :meth:`Measure.to_dict`."""
    return isinstance(entry, dict) and {"computed", "reference", "error", "tolerance", "label"} <= set(entry)


def validation_rows(phase: str, measures: dict) -> list[dict]:
    """The measures of a phase's summary as table rows, in their order."""
    return [
        {
            "phase": phase,
            "quantity": name,
            "label": entry["label"],
            "computed": entry["computed"],
            "reference": entry["reference"],
            "error": entry["error"],
            "tolerance": entry["tolerance"],
            "bound": entry.get("bound"),
            "passed": entry["passed"],
        }
        for name, entry in measures.items()
        if is_measure(entry)
    ]
