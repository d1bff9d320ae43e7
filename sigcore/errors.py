"""The root of every sigcore exception.

Each subpackage keeps its own errors in its ``exceptions.py`` (``sigcore.world.WorldError``,
``sigcore.sim.SimulationError``, ...) and the bundled plugins in theirs; every one of them derives from
:class:`SigcoreError`, and also from the built-in class that code already catches (``ApiError`` is a ``ValueError``,
``PluginError`` a ``LookupError``, ``BackendError`` a ``RuntimeError``). :class:`ApiError` (exported as
``sigcore.agent.ApiError``) is defined here so that the backend interface can refuse requests too
(``sigcore.backend.BackendRefusal``).
"""

from __future__ import annotations

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
