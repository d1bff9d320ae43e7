"""Features that fail while running: who owns what a feature subscribed, its services, and who was disabled."""

from __future__ import annotations

import logging
import traceback
from dataclasses import dataclass

from ..isolation import describe

log = logging.getLogger("sigcore")


@dataclass(frozen=True)
class FeatureOwner:
    """The owner of what a feature subscribed on the event hub (``sigcore.sim.events``): its ``<plugin>`` name."""

    name: str


@dataclass(frozen=True)
class FeatureFailure:
    """A feature raised (or called ``sys.exit``) while the simulation ran, and was disabled.

    Attributes:
        feature: The feature's name (``<plugin name="...">``).
        where: What of it was called: a subscriber of an event channel (``step observer``, ``collision observer``,
            ``message observer``, ``scan observer``, ``camera observer``, ``scene observer``...), ``reset``,
            ``entities_changed``, ``summary``, ``results``, ``report`` or ``outcome``.
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
    """The one owner of the features' viewer services and of their failures.

    A feature is disabled when something of it raises while the simulation runs: its subscriptions on the event hub
    are detached (``reset`` and ``entities_changed`` included), its services removed; the run goes on, and
    :attr:`failures` says what happened.
    """

    def __init__(self) -> None:
        self.services: dict[str, str] = {}
        """Viewer services registered by features: service name -> feature."""
        self.failures: list[FeatureFailure] = []
        self.disabled: set[str] = set()
        """Names of the features disabled so far."""

    def fail(self, feature: str, where: str, time: float, exc: BaseException) -> FeatureFailure:
        """Record that ``feature`` failed in ``where`` and is disabled; log one line (the traceback at DEBUG)."""
        failure = FeatureFailure(feature, where, time, describe(exc),
                                 "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))
        self.failures.append(failure)
        self.disabled.add(feature)
        log.error("%s; the run goes on without it", failure.line())
        log.debug("traceback of feature '%s' (%s):\n%s", feature, where, failure.traceback)
        return failure
