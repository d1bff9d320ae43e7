"""Service responses that wait for their client: a response is never dropped because discovery lags.

Why: a client's request can reach the simulator before the simulator has discovered the client's *response*
reader (the client's request writer and response reader are two DDS endpoints, discovered one after the other; on
a loaded machine seconds apart). rmw_fastrtps then waits only the response writer's ``max_blocking_time``
(100 ms) for the match and drops the response with ``RMW_RET_TIMEOUT`` ("client will not receive response"),
which rclpy turns into a ``RuntimeWarning``; the client waits for its answer forever. Seen in
``tests/ros2/test_discovery.py`` (20 clients starting with the simulator, issue 28): the simulator's log had that
warning, and clients that had found ``/get_simulation_state`` were never answered in 30 s.

:class:`Responder` sends a response at once; if rmw reports that timeout, it keeps the response and tries again
on the simulation thread between steps, a round every :data:`RETRY_PERIOD` seconds, until it goes out or
:data:`GIVE_UP` seconds have passed (then a warning names the service). A try that still times out blocks the
simulation thread up to rmw's 100 ms (as the first send already did) and ends its round, so the kept responses
cost at most 100 ms per :data:`RETRY_PERIOD` whatever their number. A client that is gone is not waited for (rmw
returns OK for it).
"""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from sigcore.api.call import log_key

log = logging.getLogger("sigcore.ros2")

RETRY_PERIOD = 0.5
"""Wall time [s] between two rounds of tries of the responses whose client's response reader was not matched yet."""

GIVE_UP = 10.0
"""A response still not sent this long [s of wall time] after its first try is dropped with a warning."""

_TIMEOUT = "failed to send response (timeout)"  # rclpy's RuntimeWarning for rmw's RMW_RET_TIMEOUT


@dataclass(eq=False)
class _Unsent:
    srv: Any
    response: Any
    header: Any
    first: float
    tries: int = 1


class Responder:
    """Sends service responses; keeps and retries those whose client is not matched yet (simulation thread)."""

    def __init__(self) -> None:
        self._unsent: list[_Unsent] = []
        self._destroys: list[tuple[Any, Callable[[], object]]] = []
        self._next = 0.0
        self.retried = 0
        """Responses that went out on a later try (each would have been lost without it)."""

    def install(self, srv: Any) -> None:
        """Make ``srv.send_response(response, header)`` go through :meth:`send` (every caller keeps its code)."""
        srv.send_response = lambda response, header: self.send(srv, response, header)

    def send(self, srv: Any, response: Any, header: Any) -> None:
        """Send ``response`` to the client of ``header`` now, or keep it for :meth:`retry` if rmw timed out."""
        if not _send(srv, response, header):
            now = time.monotonic()
            self._unsent.append(_Unsent(srv, response, header, now))
            if len(self._unsent) == 1:
                self._next = now + RETRY_PERIOD

    @property
    def due(self) -> bool:
        """Whether a kept response should be tried again now (cheap: checked every step)."""
        return bool(self._unsent) and time.monotonic() >= self._next

    def retry(self) -> None:
        """Try the kept responses again, oldest first; a round ends at the first that still times out (each such
        try blocks the simulation thread up to rmw's 100 ms), which goes to the back. Those older than
        :data:`GIVE_UP` are dropped with a warning."""
        if not self.due:
            return
        pending, kept = list(self._unsent), []
        while pending:
            u = pending.pop(0)
            try:
                sent = _send(u.srv, u.response, u.header)
            except Exception as e:  # e.g. the service was destroyed meanwhile: nothing to wait for
                log.debug("%s: a kept response was dropped (%s: %s)", u.srv.srv_name, type(e).__name__, e)
                continue
            if sent:
                self.retried += 1
                log.debug("%s: response sent on try %d, %.2f s after the first", u.srv.srv_name, u.tries + 1,
                          time.monotonic() - u.first)
                continue
            u.tries += 1
            if time.monotonic() - u.first >= GIVE_UP:
                log.warning("%s: a response was dropped: the client's response reader was not discovered within "
                            "%g s (%d tries); the client waits in vain", u.srv.srv_name, GIVE_UP, u.tries,
                            extra=log_key(u.srv.srv_name, "unsent response"))
            else:
                kept.append(u)
            break  # this client is still not matched: the others wait for the next round
        now = time.monotonic()
        expired = [u for u in pending if now - u.first >= GIVE_UP + RETRY_PERIOD]  # never reached for too long
        for u in expired:
            log.warning("%s: a response was dropped: the client's response reader was not discovered within "
                        "%g s (%d tries); the client waits in vain", u.srv.srv_name, GIVE_UP, u.tries,
                        extra=log_key(u.srv.srv_name, "unsent response"))
        self._unsent = [u for u in pending if u not in expired] + kept
        self._next = now + RETRY_PERIOD
        self._destroy_done()

    def then_destroy(self, srv: Any, destroy: Callable[[], object]) -> None:
        """Call ``destroy`` (of a retired service: nothing new reaches it) once no response of ``srv`` is kept: now,
        or after a later round sent or dropped its last (at most :data:`GIVE_UP` later). A refusal sent as the
        service is retired (its agent was deleted) is thus still tried again instead of being lost with it."""
        if any(u.srv is srv for u in self._unsent):
            self._destroys.append((srv, destroy))
        else:
            destroy()

    def _destroy_done(self) -> None:
        """Destroy the retired services whose kept responses are all gone."""
        if not self._destroys:
            return
        waiting = {id(u.srv) for u in self._unsent}
        due = [(srv, destroy) for srv, destroy in self._destroys if id(srv) not in waiting]
        self._destroys = [(srv, destroy) for srv, destroy in self._destroys if id(srv) in waiting]
        for srv, destroy in due:
            try:
                destroy()
            except Exception as e:  # destroying must never stop the simulation
                log.warning("%s: destroying a retired service failed: %s: %s", srv.srv_name, type(e).__name__, e)


def _send(srv: Any, response: Any, header: Any) -> bool:
    """rclpy's own ``Service.send_response``; False when rmw timed out waiting for the client's response reader."""
    return delivered(lambda: type(srv).send_response(srv, response, header))


def delivered(send: Callable[[], None]) -> bool:
    """Call ``send`` (an rclpy send of a response); False when rmw timed out waiting for the client's response reader.

    rclpy reports that timeout only as a ``RuntimeWarning`` (for services and for actions' services alike), so the
    warnings are caught (about 4 µs a response); any other warning is passed on. ``catch_warnings`` is process-wide: a
    warning another thread raises meanwhile is passed on from here.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        send()
    timed_out = False
    for w in caught:
        if issubclass(w.category, RuntimeWarning) and _TIMEOUT in str(w.message):
            timed_out = True
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return not timed_out
