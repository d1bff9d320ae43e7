"""Requests from outside the simulation loop, and the signal handlers that turn SIGINT/SIGTERM into one."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import FrameType

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""The signals that end a run like a QUITTING request (the run's results are kept and reported)."""


@dataclass
class RunControl:
    """Requests from outside the loop (a transport, a feature, a signal handler): pause, resume, step N, stop, reset.

    Attributes:
        paused: No steps are taken (a transport resumes).
        lockstep: Steps are taken only as ``pending_steps`` allows.
        pending_steps: Steps still to take while paused or in lockstep.
        stop: End the run after the current step; the run reports what it did.
        reset: Restore the world's initial state before the next step.
        stop_reason: Who asked to stop, when known (``"SIGINT"``, ``"SIGTERM"``; see :meth:`request_stop`).
        realtime_factor: The pace: simulated seconds per wall second (1.0: real time), None: as fast as possible.
            :func:`sigcore.sim.run` sets it from its argument and reads it at every step, so a viewer changes the
            pace while running.
    """

    paused: bool = False
    lockstep: bool = False
    pending_steps: int = 0
    stop: bool = False
    reset: bool = False
    stop_reason: str | None = None
    realtime_factor: float | None = None

    def request_stop(self, reason: str) -> None:
        """Ask the loop to end after the current step; the first ``reason`` given is kept."""
        if not self.stop and self.stop_reason is None:
            self.stop_reason = reason
        self.stop = True


@contextmanager
def stop_on_signals(control: RunControl) -> Iterator[None]:
    """While the block runs, SIGINT and SIGTERM ask ``control`` to stop instead of killing the process.

    The run then ends as after a QUITTING request: the loop finishes its step, the transport is stopped, the results
    are returned. A second signal while stopping raises :class:`KeyboardInterrupt` (abort without waiting). The
    handlers are installed even where a signal is ignored (a background job started by a shell inherits SIGINT
    ignored), and the previous handlers are restored when the block ends. Outside the main thread, where Python
    cannot install handlers, this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[str] = []

    def handler(signum: int, frame: FrameType | None) -> None:
        name = signal.Signals(signum).name
        received.append(name)
        if len(received) > 1:
            raise KeyboardInterrupt(f"{name} while stopping after {received[0]}")
        control.request_stop(name)

    previous = {signum: signal.signal(signum, handler) for signum in STOP_SIGNALS}
    try:
        yield
    finally:
        for signum, old in previous.items():
            # None: a handler installed outside Python, which cannot be put back; the default is the closest
            signal.signal(signum, old if old is not None else signal.SIG_DFL)
