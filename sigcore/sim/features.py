"""The features of one world (``<plugin>`` elements): created, asked, disabled when they fail.

:class:`FeatureHost` is ``sim.features``: a read-only mapping ``name -> Feature`` in world order, the one owner of
the features' viewer services and of their failures. What a feature subscribes on the event hub
(``sigcore.sim.events``) is owned by its :class:`FeatureOwner`; when anything of it raises while the simulation runs,
the feature is disabled: every subscription detached (``reset`` and ``entities_changed`` included), its services
removed, one line logged; the run goes on, and :attr:`FeatureHost.failures` says what happened.
"""

from __future__ import annotations

import logging
import traceback
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .. import plugins
from ..api.table import ApiEntry, api_table
from ..feature import Feature
from ..isolation import USER_ERRORS, describe
from ..text import quote
from ..world.exceptions import FieldError, WorldError, WorldIssue
from ..world.plugin_config import plugin_issue, validate_plugin
from .events import Reset, Subscriber, Subscription
from .exceptions import FeatureError

if TYPE_CHECKING:
    from .simulation import Simulation

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


class FeatureHost(Mapping[str, Feature]):
    """The features of the running world, by ``<plugin>`` name (``sim.features``), and what they registered."""

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self._features: dict[str, Feature] = {}
        self._entries: dict[str, list[ApiEntry]] = {}
        self._hooks: dict[Subscription, str] = {}  # the features' reset/entities_changed subscriptions -> hook name
        self._services: dict[str, Callable[[str, str], None]] = {}
        self._service_owner: dict[str, str] = {}  # service -> the feature that registered it
        self._connections: dict[str, set[str]] = {}  # agent -> the services it connected to
        self._creating: str | None = None  # the feature being created (its services are its own)
        self._failures: list[FeatureFailure] = []

    # ------------------------------------------------------------------ the mapping
    def __getitem__(self, name: str) -> Feature:
        return self._features[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._features)

    def __len__(self) -> int:
        return len(self._features)

    @property
    def failures(self) -> tuple[FeatureFailure, ...]:
        """The features disabled while running, in order."""
        return tuple(self._failures)

    @property
    def disabled(self) -> frozenset[str]:
        """Names of the features disabled so far."""
        return frozenset(f.feature for f in self._failures)

    # ------------------------------------------------------------------ creation
    def create(self) -> None:
        """Validate each ``<plugin>``'s attributes against its feature's ``config_model``, then create it; every
        problem is a WorldIssue at its attribute (a ``FieldError`` from a constructor names the attribute).

        Raises:
            WorldError: the problems of every ``<plugin>``, located.
            FeatureError: a feature's own code failed (its config validator or constructor).
        """
        sim, world = self._sim, self._sim.world
        issues: list[WorldIssue] = []
        for cfg in world.plugins:
            try:
                cls = plugins.get_feature(cfg.name)
                config = validate_plugin(world, cfg, cls.config_model)
            except plugins.PluginError as e:
                issues.append(plugin_issue(world, cfg, "name", str(e)))
                continue
            except WorldError as e:
                issues.extend(e.issues)
                continue
            except USER_ERRORS as e:  # its config model's own validator failed: the feature's code, not the file
                raise FeatureError(cfg.name, f"{world.source}:{cfg.line}", e) from e
            owner = FeatureOwner(cfg.name)
            self._creating = cfg.name
            try:
                with sim.events.owned_by(owner):
                    feature = self._features[cfg.name] = cls(sim, config)
                self._entries[cfg.name] = list(cls.api_entries())
                self._subscribe_hooks(owner, feature)
            except FieldError as e:
                issues.append(plugin_issue(world, cfg, e.field, str(e)))
            except (ValueError, KeyError, TypeError) as e:
                issues.append(plugin_issue(world, cfg, None, f"plugin '{cfg.name}': {e}"))
            except USER_ERRORS as e:  # not its attributes: the feature itself failed (or called sys.exit)
                raise FeatureError(cfg.name, f"{world.source}:{cfg.line}", e) from e
            finally:
                self._creating = None
            if cfg.name not in self._features:
                sim.events.detach(owner)  # what a constructor that failed had subscribed
        if issues:
            raise WorldError(issues)

    def _subscribe_hooks(self, owner: FeatureOwner, feature: Feature) -> None:
        """``feature.entities_changed`` and ``feature.reset`` on the hub's ``entities`` and ``reset`` channels, owned
        by the feature (only those it overrides: the defaults do nothing)."""
        events, cls = self._sim.events, type(feature)
        if cls.entities_changed is not Feature.entities_changed:
            self._hooks[events.subscribe("entities", feature.entities_changed, owner)] = "entities_changed"
        if cls.reset is not Feature.reset:
            def reset(_: Reset, hook: Callable[[], None] = feature.reset) -> None:
                hook()
            self._hooks[events.subscribe("reset", reset, owner)] = "reset"

    def api_entries(self) -> list[ApiEntry]:
        """The core API table plus the entries of this world's features (what transports expose)."""
        return list(api_table()) + [e for entries in self._entries.values() for e in entries]

    def entry_owner(self, entry: ApiEntry) -> str | None:
        """The feature that declared ``entry`` (None for the core's)."""
        return next((name for name, entries in self._entries.items() if any(e is entry for e in entries)), None)

    # ------------------------------------------------------------------ viewer services
    def register_service(self, name: str, handler: Callable[[str, str], None]) -> None:
        """Offer a viewer service (e.g. a referee): ``handler(sender, text)`` receives ``_send_msg_to_srv`` texts
        and raises ``ApiError`` to refuse one. A service registered while a feature is created is that feature's."""
        self._services[name] = handler
        if self._creating is not None:
            self._service_owner[name] = self._creating

    @property
    def services(self) -> Mapping[str, Callable[[str, str], None]]:
        """The viewer services offered now: name -> handler (read-only)."""
        return dict(self._services)

    def connect(self, agent: str, service: str) -> None:
        """``agent`` connected to viewer service ``service`` (``connectToService``)."""
        self._connections.setdefault(agent, set()).add(service)

    def connected(self, agent: str, service: str) -> bool:
        """Whether ``agent`` connected to ``service``."""
        return service in self._connections.get(agent, set())

    # ------------------------------------------------------------------ failures
    def owner_of(self, fn: Subscriber) -> FeatureOwner | None:
        """The owner of a subscriber subscribed without one: the feature it is a bound method of, if any."""
        instance = getattr(fn, "__self__", None)
        return next((FeatureOwner(name) for name, feature in self._features.items() if feature is instance), None)

    def contain(self, subscription: Subscription, exc: BaseException) -> bool:
        """A subscriber raised ``exc`` (``sigcore.sim.events``): disable the feature that owns it and return True, or
        False if no feature does (the hub re-raises: the core's, a transport's or a library user's error ends the
        run, with the error in its report)."""
        owner = subscription.owner
        if not isinstance(owner, FeatureOwner) or owner.name not in self._features:
            return False
        self.disable(owner.name, self._hooks.get(subscription) or f"{subscription.channel} observer", exc)
        return True

    def disable(self, feature: str, where: str, exc: BaseException) -> FeatureFailure:
        """Disable ``feature`` because ``where`` (``step observer``, ``reset``...) raised ``exc``: everything it
        subscribed on the hub is detached (not called again, even by a delivery in progress; its ``reset`` and
        ``entities_changed`` included), its viewer services removed; its ``summary``, ``report`` and ``outcome``
        are still asked at the end. Logged in one line (the traceback at DEBUG).

        Returns:
            The failure, also in :attr:`failures` and the run's report.
        """
        if feature not in self._features:
            raise KeyError(f"no feature {quote(feature)}; features: {', '.join(self._features) or 'none'}")
        failure = FeatureFailure(feature, where, self._sim.time, describe(exc),
                                 "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))
        self._failures.append(failure)
        log.error("%s; the run goes on without it", failure.line())
        log.debug("traceback of feature '%s' (%s):\n%s", feature, where, failure.traceback)
        self._sim.events.detach(FeatureOwner(feature))
        for service in [name for name, owner in self._service_owner.items() if owner == feature]:
            self._services.pop(service, None)
        return failure

    def detach_all(self) -> None:
        """Detach what every feature subscribed (the world is going)."""
        for name in self._features:
            self._sim.events.detach(FeatureOwner(name))
        self._hooks.clear()

    # ------------------------------------------------------------------ asking every feature
    def ask(self, method: str) -> dict[str, Any]:
        """Call ``method`` (``summary``, ``results``, ``report`` or ``outcome``) of every feature, in world order.

        Returns:
            ``name -> answer`` of the features that answered; a feature that raises is disabled (``where`` is the
            method) and left out.
        """
        answers = {}
        for name, feature in self._features.items():
            try:
                answers[name] = getattr(feature, method)()
            except USER_ERRORS as e:
                self.disable(name, method, e)
        return answers

    def summary(self) -> dict[str, Any]:
        """What each feature reports at the end of a run (``Feature.summary``)."""
        return self.ask("summary")

    def results(self) -> dict[str, Any]:
        """What each feature gives a program at the end of a run (``Feature.results``)."""
        return self.ask("results")

    def report_lines(self) -> list[str]:
        """The features' report lines (``Feature.report``), in world order."""
        return [str(line) for lines in self.ask("report").values() for line in lines]

    def outcome(self) -> bool | None:
        """The world's verdict from the features' ``outcome``: False if any says False, or raises (no verdict can
        be trusted then); else True if any says True; else None."""
        verdicts = self.ask("outcome")
        values = list(verdicts.values()) + [False] * (len(self._features) - len(verdicts))
        return False if False in values else True if True in values else None
