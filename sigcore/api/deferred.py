"""Responses that complete later in simulated time (e.g. "move the arm there and report the final error")."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


class Deferred:
    """Returned by a handler whose answer needs the simulation to run on.

    The simulation keeps stepping; whoever holds the Deferred (a transport, or :func:`sigcore.api.wait` in Python)
    calls :meth:`poll` after each step until it returns the response fields. Never block in a handler.

    Args:
        poll: Called after each step; returns the response fields (a dict) when done, else ``None``. It may raise
            ``ApiError`` to refuse (the response then says why).
        timeout: Simulated seconds after which the request fails with a timeout message [s].
        start: Simulation time when the request was made [s].
    """

    def __init__(self, poll: Callable[[], dict[str, Any] | None], timeout: float, start: float) -> None:
        self._poll = poll
        self.deadline = start + timeout
        self.timeout = timeout

    def poll(self, time: float) -> dict[str, Any] | None:
        """The response fields once done (``success``/``message`` included by the caller), else ``None``.

        Raises:
            TimeoutError: ``time`` is past the deadline and the request is not done.
        """
        result = self._poll()
        if result is None and time > self.deadline:
            raise TimeoutError(f"not done after {self.timeout:g} s of simulated time")
        return result
