"""What sigcore catches around every call into user or plugin code, and how it names what was caught.

A controller, a feature or a plugin may raise anything, and may call ``sys.exit`` (``SystemExit``): sigcore catches
both, names the culprit, disables it and goes on. ``KeyboardInterrupt`` is never caught here: Ctrl-C belongs to the
user, and :func:`sigcore.sim.run` turns it into a stop request.
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import BudgetError

USER_ERRORS: tuple[type[BaseException], ...] = (Exception, SystemExit)
"""What a call into user or plugin code may raise that sigcore catches (``except USER_ERRORS``)."""


def describe(exc: BaseException) -> str:
    """One line saying what ``exc`` is: ``Type: message``; for ``SystemExit``, that ``sys.exit`` was called.

    Args:
        exc: What the user's or plugin's code raised.

    Returns:
        E.g. ``RuntimeError: boom`` or ``SystemExit: sys.exit(3) was called``.
    """
    if isinstance(exc, SystemExit):
        return f"SystemExit: sys.exit({exc.code!r}) was called" if exc.code is not None else \
            "SystemExit: sys.exit() was called"
    return f"{type(exc).__name__}: {exc}"


CALLBACK_BUDGET = 1.0
"""Default wall-clock budget of one controller callback [s]: a callback that takes longer stalls the whole
simulation (and, at real time, every client), so it is reported with its agent's name."""


@dataclass(frozen=True)
class CallbackBudget:
    """How long one controller callback may take in wall-clock time, and what happens when it takes longer.

    Python code cannot be interrupted in the simulation thread: the budget is checked after the callback returns.
    Measuring costs two ``perf_counter`` calls per callback (about 0.1 µs), nothing on steps without a callback.

    Attributes:
        seconds: The budget [s] (wall-clock); 0 turns the check off; ``BudgetError`` if negative or NaN.
        disable: Disable a controller whose callback took longer (after the call returned), as if it had raised;
            otherwise it is only reported (a warning the first time, a line in the run's report).
    """

    seconds: float = CALLBACK_BUDGET
    disable: bool = False

    def __post_init__(self) -> None:
        if not (self.seconds >= 0):  # NaN too
            raise BudgetError(f"the callback budget must be a number of seconds >= 0 (0: no budget), got "
                              f"{self.seconds}")


