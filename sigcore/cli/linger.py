"""``sigcore run --viewer``: the page after the run (``--viewer-linger``).

When the run ends by itself (the referee ended the task, ``--duration`` or ``--steps`` reached, a QUITTING request,
an error), the viewer's page keeps showing the last moment, the result and the score table, and the process waits
before it exits (with the task's verdict as exit code, as without a viewer) until, whichever comes first:

* Enter (or end of input) in the terminal, when the run has one (its standard input and error are terminals);
* the last browser page showing it closed;
* a signal (Ctrl-C, SIGTERM);
* ``--viewer-linger S`` seconds.

Without ``--viewer-linger`` the wait has no time limit when the run has a terminal, and there is none without one
(under ``sigcore eval``, CI, a test, a script with its output piped): such a run ends as it always did. A run ended
by a signal does not wait: Ctrl-C is the person's "enough".
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import sys
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, TextIO

if TYPE_CHECKING:
    from ..sim.runner import RunReport
    from ..viewer import Viewer


def has_terminal() -> bool:
    """Whether a person can answer in a terminal: standard input and standard error are both terminals."""
    try:
        return os.isatty(sys.stdin.fileno()) and os.isatty(sys.stderr.fileno())
    except (AttributeError, OSError, ValueError):  # closed or replaced streams
        return False


def linger_seconds(option: float | None, terminal: bool) -> float | None:
    """How long the page stays after the run [s]: ``--viewer-linger`` when given; else no limit (None) with a
    terminal and 0 without one."""
    if option is not None:
        return option
    return None if terminal else 0.0


def how_it_ended(report: RunReport) -> str:
    """One line for the page: why the run stopped and the verdict."""
    why = {None: "ran its --duration / --steps", "request": "stopped by a request (the task's end, or QUITTING)",
           "error": f"stopped by an error: {report.error}"}.get(report.stopped_by, f"stopped by {report.stopped_by}")
    verdict = {None: "no verdict", True: "the task succeeded", False: "the task failed"}[report.outcome]
    return f"{why}; {verdict}; exit code {report.exit_code}"


def linger(viewer: Viewer, report: RunReport, seconds: float | None, terminal: bool,
           say: Callable[[str], None]) -> str:
    """Keep ``viewer``'s page up after the run (see the module), then close it; returns why the wait ended."""
    if report.stopped_by in ("SIGINT", "SIGTERM") or seconds == 0:
        viewer.close()
        return "not held"
    limit = "" if seconds is None else f" (at most {seconds:g} s)"
    keys = "press Enter here, " if terminal else ""
    # the handlers first: a signal sent as soon as the person is told it ends the wait must find them (it killed the
    # process once, in CI, when they came after the message)
    with _signals() as signalled:
        say(f"viewer: the run has ended; the page shows its last moment, the result and the score table{limit}: "
            f"{keys}close the page or press Ctrl-C to exit")
        done = _enter(sys.stdin, signalled) if terminal else signalled
        return viewer.linger(how_it_ended(report), report.report_lines, seconds, done)


@contextlib.contextmanager
def _signals() -> Iterator[Callable[[], bool]]:
    """While the page lingers, SIGINT and SIGTERM end the wait (not the process: the verdict is still returned)."""
    got: list[int] = []
    handlers = {s: signal.signal(s, lambda n, _f: got.append(n)) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: bool(got)
    finally:
        for s, handler in handlers.items():
            signal.signal(s, handler)


def _enter(stream: TextIO, signalled: Callable[[], bool]) -> Callable[[], bool]:
    """A check that is true once a line (Enter) or the end of input arrived on ``stream``, or a signal."""
    def check() -> bool:
        if signalled():
            return True
        try:
            ready, _, _ = select.select([stream], [], [], 0)
            return bool(ready) and stream.readline() is not None
        except (OSError, ValueError):
            return True
    return check
