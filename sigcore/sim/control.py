"""The run's state machine (play, pause, step, reset, pace, stop), and the signal handlers that stop a run."""

from __future__ import annotations

import math
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import FrameType
from typing import Literal

from .exceptions import RunStateError

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""The signals that end a run like a QUITTING request (the run's results are kept and reported)."""


Verb = Literal["play", "pause", "step", "reset", "pace", "stop"]


@dataclass(frozen=True)
class ControlChange:
    """The payload of the simulation's ``control`` event: ``verb`` was done, and the run control is now so.

    Attributes:
        verb: ``play``, ``pause``, ``step``, ``reset``, ``pace`` or ``stop``.
        paused: No steps are taken but the pending ones.
        pending_steps: Steps still to take while paused.
        stopping: The run ends after the current step.
        realtime_factor: The pace (None: as fast as possible).
        step: The world's step count when the verb was done.
    """

    verb: Verb
    paused: bool
    pending_steps: int
    stopping: bool
    realtime_factor: float | None
    step: int


class RunControl:
    """The run's state and the verbs that change it. Every client (a viewer, simulation_interfaces, the CLI, a
    referee, a replay, the signal handlers) calls the verbs, so play, pause, step and reset mean one thing everywhere:

    - :meth:`play`: steps are taken freely (at the pace); steps still pending are dropped.
    - :meth:`pause`: no steps are taken; steps still pending are dropped.
    - :meth:`step` ``(n)``: pause, and take ``n`` more steps (added to those pending), then stay paused.
    - :meth:`request_reset`: restore the world's initial state now (between steps, on the simulation thread, where
      every client's commands run); playing or paused, the steps pending and the pace are kept; time goes on.
    - :meth:`set_pace`: simulated seconds per wall second (None: as fast as possible), from the next step on.
    - :meth:`stop` ``(reason)``: end the run after the current step; the first reason is kept.

    The state is read-only (:attr:`paused`, :attr:`pending_steps`, :attr:`stopping`, :attr:`stop_reason`,
    :attr:`realtime_factor`). Each verb is told to ``on_change`` (the simulation's ``control`` event); the run loop's
    bookkeeping (:meth:`take_step`) and the core's (:meth:`hold`, :meth:`drop_steps`) are not verbs and are not told.

    Args:
        paused: Start paused.
        realtime_factor: The start pace.
        loaded: Whether a world is loaded (play, step and reset need one); default: always.
        reset: Restores the world's initial state (its argument: ``despawn``, see ``Simulation.reset``).
        on_change: Told of every verb done.
        step_count: The world's step count (for :class:`ControlChange`).
    """

    def __init__(self, paused: bool = False, realtime_factor: float | None = None,
                 loaded: Callable[[], bool] | None = None, reset: Callable[[bool], None] | None = None,
                 on_change: Callable[[ControlChange], None] | None = None,
                 step_count: Callable[[], int] | None = None) -> None:
        self._paused = paused
        self._pending = 0
        self._stopping = False
        self._stop_reason: str | None = None
        self._pace = realtime_factor
        self._loaded = loaded
        self._reset = reset
        self._on_change = on_change
        self._step_count = step_count

    # ------------------------------------------------------------------ state
    @property
    def paused(self) -> bool:
        """No steps are taken but the :attr:`pending_steps`."""
        return self._paused

    @property
    def pending_steps(self) -> int:
        """Steps still to take while paused (:meth:`step`)."""
        return self._pending

    @property
    def idle(self) -> bool:
        """Paused with no step pending: nothing steps until a verb says so."""
        return self._paused and self._pending <= 0

    @property
    def stopping(self) -> bool:
        """The run ends after the current step (:meth:`stop`)."""
        return self._stopping

    @property
    def stop_reason(self) -> str | None:
        """Who asked to stop: ``"SIGINT"``, ``"SIGTERM"``, ``"request"`` (QUITTING, the referee), ...; None before."""
        return self._stop_reason

    @property
    def realtime_factor(self) -> float | None:
        """The pace: simulated seconds per wall second (1.0: real time), None: as fast as possible."""
        return self._pace

    # ------------------------------------------------------------------ verbs
    def play(self) -> None:
        """Take steps freely, at the pace; pending steps are dropped.

        Raises:
            RunStateError: no world is loaded.
        """
        self._need_world("play")
        self._paused, self._pending = False, 0
        self._told("play")

    def pause(self) -> None:
        """Take no more steps; pending steps are dropped (also without a world: it stays paused)."""
        self._paused, self._pending = True, 0
        self._told("pause")

    def step(self, n: int) -> None:
        """Pause, and take ``n`` more steps (added to those pending).

        Raises:
            RunStateError: ``n`` is not a whole number of at least 1, or no world is loaded.
        """
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise RunStateError(f"steps must be a whole number of at least 1, got {n!r}")
        self._need_world("step")
        self._paused = True
        self._pending += n
        self._told("step")

    def request_reset(self, despawn: bool = True) -> None:
        """Restore the world's initial state now (``despawn``: also delete what was spawned and bring back what was
        deleted); playing or paused, the steps pending and the pace stay as they were.

        Raises:
            RunStateError: no world is loaded.
        """
        self._need_world("reset")
        if self._reset is not None:
            self._reset(despawn)
        self._told("reset")

    def set_pace(self, realtime_factor: float | None) -> None:
        """Simulated seconds per wall second from the next step on (None: as fast as possible).

        Raises:
            RunStateError: neither a positive finite number nor None.
        """
        if realtime_factor is not None and (isinstance(realtime_factor, bool)
                                            or not isinstance(realtime_factor, int | float)
                                            or not math.isfinite(realtime_factor) or realtime_factor <= 0):
            raise RunStateError(f"the pace must be a positive number of simulated seconds per wall second, or None "
                                f"(as fast as possible), got {realtime_factor!r}")
        self._pace = realtime_factor
        self._told("pace")

    def stop(self, reason: str = "request") -> None:
        """End the run after the current step; the first ``reason`` given is kept (``RunReport.stopped_by``)."""
        if self._stop_reason is None:
            self._stop_reason = reason
        self._stopping = True
        self._told("stop")

    # ------------------------------------------------------------------ the run loop's and the core's bookkeeping
    def take_step(self) -> bool:
        """Whether the loop may take a step now: playing, or paused with a step pending (then one fewer)."""
        if not self._paused:
            return True
        if self._pending <= 0:
            return False
        self._pending -= 1
        return True

    def drop_steps(self, n: int) -> None:
        """Drop up to ``n`` pending steps (a step request cancelled before they were taken)."""
        self._pending = max(0, self._pending - max(0, n))

    def hold(self) -> None:
        """A world was just loaded or unloaded: paused at its time 0, nothing pending."""
        self._paused, self._pending = True, 0

    def rearm(self) -> None:
        """Forget a stop, so that another run may start with this control (a program that runs the same simulation
        several times)."""
        self._stopping, self._stop_reason = False, None

    def _need_world(self, verb: str) -> None:
        if self._loaded is not None and not self._loaded():
            raise RunStateError(f"no world is loaded: nothing to {verb}; load one first (load_world)")

    def _told(self, verb: Verb) -> None:
        if self._on_change is not None:
            step = self._step_count() if self._step_count is not None else 0
            self._on_change(ControlChange(verb, self._paused, self._pending, self._stopping, self._pace, step))

    def __repr__(self) -> str:
        return (f"RunControl(paused={self._paused}, pending_steps={self._pending}, stopping={self._stopping}, "
                f"realtime_factor={self._pace})")


@contextmanager
def stop_on_signals(control: RunControl) -> Iterator[None]:
    """While the block runs, SIGINT and SIGTERM ask ``control`` to stop instead of killing the process.

    The run then ends as after a QUITTING request: the loop finishes its step, the transport is stopped, the results
    are returned. A second signal while stopping raises :class:`KeyboardInterrupt` (abort without waiting). The
    handlers are installed even where a signal is ignored (a background job started by a shell inherits SIGINT
    ignored) or blocked (inherited from a parent's thread that blocked it), and the previous handlers (and mask) are
    restored when the block ends. Outside the main thread, where Python
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
        control.stop(name)

    previous = {signum: signal.signal(signum, handler) for signum in STOP_SIGNALS}
    blocked = signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS) & set(STOP_SIGNALS)  # inherited blocked
    try:
        yield
    finally:
        for signum, old in previous.items():
            # None: a handler installed outside Python, which cannot be put back; the default is the closest
            signal.signal(signum, old if old is not None else signal.SIG_DFL)
        if blocked:
            signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
