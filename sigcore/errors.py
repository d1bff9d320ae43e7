"""The root of every sigcore exception.

Each subpackage keeps its own errors in its ``exceptions.py`` (``sigcore.world.WorldError``,
``sigcore.sim.SimulationError``, ...) and the bundled plugins in theirs; every one of them derives from
:class:`SigcoreError`, and also from the built-in class that code already catches (``ApiError`` is a ``ValueError``,
``PluginError`` a ``LookupError``, ``BackendError`` a ``RuntimeError``). :class:`ApiError` (exported as
``sigcore.agent.ApiError``) is defined here so that the backend interface can refuse requests too
(``sigcore.errors.BackendRefusal``).
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .plugins import PluginInfo

from collections.abc import Mapping
from typing import Any


class SigcoreError(Exception):
    """Base class of every error sigcore and its bundled plugins raise on purpose (catch this to catch them all)."""


class ApiError(SigcoreError, ValueError):
    """A request to the agent API was refused (unknown name, NaN, out of range, wrong mode...).

    The simulation is unaffected; transports turn this into an error response.

    Args:
        message: What was wrong and what would be valid.
        fields: Response fields the error response carries besides ``success`` and ``message`` (e.g. the residual
            of a failed IK solve); those the response type does not have are dropped. Empty by default.
    """

    def __init__(self, message: str = "", fields: Mapping[str, Any] | None = None) -> None:
        super().__init__(message)
        self.fields: dict[str, Any] = dict(fields or {})


class TransportError(SigcoreError):
    """A transport refused what it was asked before or while starting: arguments it does not take or that are
    wrong, a question it cannot answer. The message names what was wrong and what is valid."""


class PublicationError(SigcoreError, ValueError):
    """A publication cannot be declared (bad name or type, a name taken by another type) or a value pushed."""


class PluginError(SigcoreError, LookupError):
    """A name that no plugin registered; the message lists the registered names and the failed plugins.

    Attributes:
        kind: ``backend``, ``transport``, ``feature`` or ``controller``.
        name: The name asked for.
        available: The registered names of that kind, sorted.
        failed: Plugins that failed to load (one of them may have provided ``name``).
    """

    def __init__(self, kind: str, name: str, available: Sequence[str],
                 failed: Sequence[PluginInfo] = ()) -> None:
        self.kind, self.name, self.available, self.failed = kind, name, list(available), list(failed)
        message = f"{kind} '{name}' is not registered; available: {', '.join(self.available) or 'none'}"
        close = difflib.get_close_matches(name, self.available, n=1)
        if close:
            message += f" (did you mean '{close[0]}'?)"
        elif not self.available:
            message += f" (install a sigcore plugin that provides a {kind}; `sigcore plugins` lists them)"
        if self.failed:
            failures = "; ".join(f"{i.describe()}: {i.error}" for i in self.failed)
            message += f"; plugins that failed to load: {failures}"
        super().__init__(message)


class PluginLoadError(SigcoreError, RuntimeError):
    """:func:`register_plugin` refused a plugin; ``info`` says which and why."""

    def __init__(self, info: PluginInfo) -> None:
        self.info = info
        super().__init__(f"plugin {info.describe()} failed to load: {info.error}")


class BackendError(SigcoreError, RuntimeError):
    """The backend could not do what was asked; the message says why and what would be valid."""


class BackendRefusal(BackendError, ApiError):
    """A request on the running world that the backend refuses because of what was asked, not because the backend
    failed: an unknown entity, part or joint, dynamics for a static object, a position target for a drive wheel,
    a mass for a body without one. The API answers it like any refusal: one line, no traceback (an
    :class:`~sigcore.agent.exceptions.ApiError`); it is still a :class:`BackendError` for callers of the backend."""


class BudgetError(SigcoreError, ValueError):
    """A :class:`CallbackBudget` that is not a number of seconds >= 0."""


class ViewerError(TransportError):
    """A viewer cannot start as asked (e.g. its port is taken); the message names what and what would work."""
