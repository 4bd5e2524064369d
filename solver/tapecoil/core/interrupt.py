"""Graceful stops: a signal ends a run after its current step, with its checkpoint written.

SIGINT (Ctrl-C), SIGTERM and SIGUSR1 only set a flag; the stepping loops ask
:meth:`StopSignals.requested` after every converged step, collectively, so that all ranks stop
after the same step, write the checkpoint of that (converged) state and end with
:class:`Interrupted`. ``--resume`` continues from it.

Under ``mpirun`` (Open MPI 5) SIGINT and SIGTERM sent to mpirun kill the ranks at once; mpirun
forwards SIGUSR1, so ``kill -USR1 <pid of mpirun>`` stops a parallel run gracefully. A hard kill
still leaves the last periodic checkpoint (``output.checkpoint_every``).
"""

from __future__ import annotations

import signal
import threading

from mpi4py import MPI

SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)


class Interrupted(Exception):
    """A run stopped on a signal after a converged step; ``signum`` is the signal."""

    def __init__(self, signum: int):
        super().__init__(f"stopped by {signal.Signals(signum).name} after a converged step")
        self.signum = signum

    @property
    def name(self) -> str:
        return signal.Signals(self.signum).name


class StopSignals:
    """Context manager: while active, the signals of :data:`SIGNALS` request a stop.

    Outside the main thread (where Python cannot install handlers) it does nothing and no stop
    is ever requested.
    """

    def __init__(self):
        self.received = 0
        self._previous: dict[int, object] = {}

    def _handle(self, signum, _frame) -> None:
        self.received = signum

    def __enter__(self) -> StopSignals:
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNALS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()

    def requested(self, comm=MPI.COMM_WORLD) -> int:
        """The signal any rank has received (0: none). Collective: every rank must call it."""
        return comm.allreduce(self.received, op=MPI.MAX)

    def check(self, comm=MPI.COMM_WORLD) -> None:
        """Raise :class:`Interrupted` on every rank if any rank has received a signal (collective)."""
        signum = self.requested(comm)
        if signum:
            raise Interrupted(signum)
