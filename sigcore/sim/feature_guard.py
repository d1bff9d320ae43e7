"""Features that fail while running: which feature owns which observer and service, and who was disabled."""

from __future__ import annotations

import logging
import traceback
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TypeVar, cast

from ..isolation import describe

log = logging.getLogger("sigcore")
T = TypeVar("T")

OBSERVER_LISTS = ("_step_observers", "collision_observers", "message_observers", "scan_observers",
                  "camera_observers")
"""The simulation's observer lists (attribute names) that features attach to."""


def _detached(_: object) -> None:
    """Put in place of a disabled feature's observer in a list that may be being iterated (then replaced)."""


@dataclass(frozen=True)
class FeatureFailure:
    """A feature raised (or called ``sys.exit``) while the simulation ran, and was disabled.

    Attributes:
        feature: The feature's name (``<plugin name="...">``).
        where: What of it was called: ``step observer``, ``collision observer``, ``message observer``, ``scan
            observer``, ``reset``, ``summary``, ``report`` or ``outcome``.
        time: Simulation time [s].
        error: ``Type: message`` of the exception.
        traceback: The formatted traceback (logged at DEBUG; the report shows one line).
    """

    feature: str
    where: str
    time: float
    error: str
    traceback: str

    def line(self) -> str:
        """The report's line: ``feature 'x' disabled (step observer at t=1.000 s): RuntimeError: ...``."""
        return f"feature '{self.feature}' disabled ({self.where} at t={self.time:.3f} s): {self.error}"


class FeatureGuard:
    """The one owner of what features attached to the simulation (observers, services) and of their failures.

    A feature is disabled when something of it raises while the simulation runs: its observers are detached, its
    services removed, ``reset`` is no longer called; the run goes on, and :attr:`failures` says what happened.
    """

    def __init__(self) -> None:
        self._observers: dict[int, tuple[str, object]] = {}  # id -> (feature, the observer, kept alive)
        self.services: dict[str, str] = {}
        """Viewer services registered by features: service name -> feature."""
        self.failures: list[FeatureFailure] = []
        self.disabled: set[str] = set()
        """Names of the features disabled so far."""

    def adopt(self, feature: str, observers: Iterable[object], services: Iterable[str]) -> None:
        """Record ``observers`` and ``services`` (attached while ``feature`` was being created) as ``feature``'s."""
        for observer in observers:
            self._observers[id(observer)] = (feature, observer)
        for service in services:
            self.services[service] = feature

    def owner(self, observer: object, features: Mapping[str, object]) -> str | None:
        """The feature that attached ``observer``: recorded while it was created, or the instance ``observer`` is
        a method of; None for the core's, a transport's or a library user's observers."""
        entry = self._observers.get(id(observer))
        if entry is not None and entry[1] is observer:
            return entry[0]
        instance = getattr(observer, "__self__", None)  # a bound method attached after construction
        return next((name for name, feature in features.items() if feature is instance), None)

    def detach(self, feature: str, observers: list[T], features: Mapping[str, object]) -> list[T]:
        """``observers`` without ``feature``'s. Those are also replaced by a no-op in ``observers`` itself, so that a
        loop running over it now (the failure happened inside it) does not call them again.

        Args:
            feature: The feature being disabled.
            observers: One of the simulation's observer lists.
            features: The simulation's features by name (see :meth:`owner`).

        Returns:
            A new list to use from now on (``observers`` itself when the feature had none in it).
        """
        mine = [i for i, o in enumerate(observers) if self.owner(o, features) == feature]
        if not mine:
            return observers
        for i in mine:
            observers[i] = cast(T, _detached)
        return [o for o in observers if o is not _detached]

    def fail(self, feature: str, where: str, time: float, exc: BaseException) -> FeatureFailure:
        """Record that ``feature`` failed in ``where`` and is disabled; log one line (the traceback at DEBUG)."""
        failure = FeatureFailure(feature, where, time, describe(exc),
                                 "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))
        self.failures.append(failure)
        self.disabled.add(feature)
        log.error("%s; the run goes on without it", failure.line())
        log.debug("traceback of feature '%s' (%s):\n%s", feature, where, failure.traceback)
        return failure
