"""What a phase's run keeps around its stepping: the history, its wall clock, the step callback, the stop.

The coiling and the deployment runs (:mod:`tapecoil.phases.coiling_run`,
:mod:`tapecoil.phases.deployment_run`) step and measure differently, and keep their histories
alike: a row per converged step, timed by the run's wall clock and handed to ``on_step``; a
restarted run continues the history and the wall time of the one that stopped.
"""

from __future__ import annotations

import time


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
        return {"history": h, "wall_time_before": h[-1]["wall_time"] if h else 0.0}

    def _restore_history(self, state: dict) -> None:
        """Continue the history and the wall clock of :meth:`_history_state`."""
        self.result.history = list(state["history"])
        self._t0 -= state["wall_time_before"]

    def _check_stop(self, comm) -> None:
        """Raise :class:`~tapecoil.core.interrupt.Interrupted` if a stop signal came (collective)."""
        if self.stop is not None:
            self.stop.check(comm)
