"""A start without races: hold a simulation paused at its start until the named topics have their peers.

``sigcore run WORLD --wait-for /clock --wait-for /robot_000/cmd_vel`` starts the simulation paused at t = 0 (the
transport keeps publishing the unchanged time, as it does paused) and plays it by itself once every named topic has
at least N matched subscribers (a topic the simulation publishes) or publishers (a topic it subscribes to), so that
nodes started with the simulator do not miss its beginning. A client may still set PLAYING itself.
"""

from __future__ import annotations

import logging
import re
import time
from collections.abc import Callable
from dataclasses import dataclass

from ..transport import Transport
from .control import RunControl

__all__ = ["REMIND_EVERY", "SETTLE", "StartGate", "WaitFor"]

SETTLE = 0.3
"""Once every topic has its peers, stay paused this much longer [s of wall time]: the subscriber's side of a match
may lag the publisher's, and a message sent before it completes would be lost (volatile topics)."""

REMIND_EVERY = 10.0
"""While waiting, say so again this often [s of wall time]."""

POLL_EVERY = 0.05
"""Count the peers at most this often [s of wall time]."""


@dataclass(frozen=True)
class WaitFor:
    """One topic to wait for.

    Attributes:
        topic: The topic's full name, as ``sigcore api WORLD`` lists it (before any remapping).
        count: Peers it needs (at least 1).
    """

    topic: str
    count: int = 1

    @classmethod
    def parse(cls, text: str) -> WaitFor:
        """``TOPIC`` or ``TOPIC=N`` (a relative name is taken from the root: ``clock`` = ``/clock``).

        Raises:
            ValueError: not of that form, or N is not an integer >= 1 (the message says what is valid).
        """
        topic, sep, count = text.partition("=")
        topic = topic.strip()
        if not re.fullmatch(r"/?[A-Za-z0-9_~{}/]+", topic):
            raise ValueError(f"'{text}' is not TOPIC or TOPIC=N; valid: e.g. /clock or /robot_000/cmd_vel=1")
        if sep and not re.fullmatch(r"[0-9]+", count.strip()):
            raise ValueError(f"'{text}': N = '{count}' is not an integer; valid: TOPIC=N with N >= 1")
        n = int(count) if sep else 1
        if n < 1:
            raise ValueError(f"'{text}': N = {n}; valid: TOPIC=N with N >= 1 (subscribers or publishers)")
        return cls(topic if topic.startswith("/") else "/" + topic, n)


class StartGate:
    """Holds ``control`` paused until every :class:`WaitFor` has its peers (or ``timeout`` passed).

    The runner calls :meth:`poll` between steps while the gate is :attr:`active`. It plays the simulation
    (``control.play()``) when every topic has had its peers for :data:`SETTLE` seconds, or after
    ``timeout`` seconds with a warning; it lets go at once when something else played it (a client's PLAYING).

    Args:
        waits: The topics and how many peers each needs.
        timeout: Play anyway after this many seconds of wall time [s]; 0: wait forever.
        say: Where the waiting lines go (``sigcore run``: stderr; default: the ``sigcore`` logger, WARNING).
        clock: Wall clock [s] (``time.monotonic``).
    """

    def __init__(self, waits: list[WaitFor], timeout: float = 0.0, say: Callable[[str], None] | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if timeout < 0:
            raise ValueError(f"timeout {timeout:g} s; valid: >= 0 [s] (0: wait forever)")
        self.waits = list(waits)
        self.timeout = timeout
        self.say = say or logging.getLogger("sigcore").warning
        self.clock = clock
        self.active = bool(self.waits)
        """Whether the gate still holds the simulation (False once it played, or a client did)."""
        self.outcome: str | None = None
        """How the wait ended: ``"matched"``, ``"timeout"`` or ``"client"`` (None while waiting)."""
        self._start: float | None = None
        self._next_poll = 0.0
        self._next_say = 0.0
        self._met: float | None = None

    def poll(self, control: RunControl, transport: Transport) -> None:
        """Count the peers (at most every :data:`POLL_EVERY` s) and play when every topic has them.

        Raises:
            TransportError: the transport cannot count the peers of a topic.
        """
        if not self.active:
            return
        now = self.clock()
        if self._start is None:
            self._start = now
        if not control.paused:  # a client set PLAYING (or another part of the run did)
            self._end("client", "no longer waiting: the simulation was set playing")
            return
        if now < self._next_poll:
            return
        self._next_poll = now + POLL_EVERY
        missing = []
        for wait in self.waits:
            n, role = transport.matched(wait.topic)
            if n < wait.count:
                missing.append(f"{wait.count} {role}{'s' if wait.count > 1 else ''} of {wait.topic} ({n} so far)")
        if not missing:
            if self._met is None:
                self._met = now
            if now - self._met >= SETTLE:
                control.play()
                self._end("matched", "every awaited topic has its peers: playing")
            return
        self._met = None
        waited = now - self._start
        if self.timeout and waited >= self.timeout:
            control.play()
            self._end("timeout", f"warning: playing after --wait-timeout {self.timeout:g} s although still "
                                 f"missing: {', '.join(missing)}")
            return
        if now >= self._next_say:
            self._next_say = now + REMIND_EVERY
            self.say(f"waiting for {', '.join(missing)}; paused until then"
                     + (f" (waited {waited:.0f} s)" if waited >= 1 else ""))

    def _end(self, outcome: str, line: str) -> None:
        self.active = False
        self.outcome = outcome
        self.say(line)
