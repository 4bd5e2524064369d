"""What a phase's run keeps around its stepping: the history, its wall clock, the step callback, the stop.

The coiling and the deployment runs (:mod:`tapecoil.phases.coiling_run`,
:mod:`tapecoil.phases.deployment_run`) step and measure differently, and keep their histories
alike: a row per converged step, timed by the run's wall clock and handed to ``on_step``; a
restarted run continues the history and the wall time of the one that stopped.
"""

from __future__ import annotations

import time

# a step grows after one that converged in at most this many Newton iterations, in every phase's
# stepping (the full shell's and the hybrid's): a stricter bound keeps the steps short where the
# coiling and the deployment would take longer ones, for more steps in all
EASY_ITERATIONS = 8


def last_wall_time(rows) -> float:
    """The wall time [s] of the last of ``rows`` (history dicts, or records with a ``wall_time``),
    0 with none: what a stopped run had spent, for its restart."""
    if not rows:
        return 0.0
    last = rows[-1]
    return last["wall_time"] if isinstance(last, dict) else last.wall_time


def clock_origin(wall_time_before: float, started: float | None = None) -> float:
    """The origin (a ``time.perf_counter()``) of a run's wall clock started at ``started`` (now
    if None) that had spent ``wall_time_before`` [s] before it stopped: a restarted run's rows go
    on counting from the stopped run's last."""
    return (time.perf_counter() if started is None else started) - wall_time_before


class SteppedRun:
    """The history of ``result`` (a dataclass with a ``history`` list) and what goes with it.

    ``on_step(row)`` is called on every rank with each new row; ``stop``
    (:class:`~tapecoil.core.interrupt.StopSignals`) is checked after every converged step.
    """

    def __init__(self, result, on_step=None, stop=None):
        self.result = result
        self.on_step = on_step
        self.stop = stop
        self._t0 = time.perf_counter()

    def _record(self, row: dict) -> dict:
        """Time ``row`` by the run's wall clock, add it to the history and hand it to ``on_step``."""
        row["wall_time"] = time.perf_counter() - self._t0
        self.result.history.append(row)
        if self.on_step is not None:
            self.on_step(row)
        return row

    def _history_state(self) -> dict:
        """The history and the wall time spent, for a restart state."""
        h = self.result.history
        return {"history": h, "wall_time_before": last_wall_time(h)}

    def _restore_history(self, state: dict) -> None:
        """Continue the history and the wall clock of :meth:`_history_state`."""
        self.result.history = list(state["history"])
        self._t0 = clock_origin(state["wall_time_before"], started=self._t0)

    def _check_stop(self, comm) -> None:
        """Raise :class:`~tapecoil.core.interrupt.Interrupted` if a stop signal came (collective)."""
        if self.stop is not None:
            self.stop.check(comm)
