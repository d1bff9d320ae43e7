"""The agents' publications of one world: one per agent for every ``publish`` entry of the API table, with the
source of its values (``sigcore.api.sources``), and the robots' ``robot_description`` and the scene
(``sigcore.sim.description``).

What a source subscribes on the event hub is its feature's (detached if that feature is disabled) or, for the
core's entries, the world's own parts (:class:`WorldParts`), detached when the world goes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

from ..api.sources import Source
from ..publish import Publication, Publisher
from .description import DescriptionTopics
from .features import FeatureOwner

if TYPE_CHECKING:
    from .simulation import Simulation


class WorldParts:
    """The owner of what one world's own parts subscribed (its description topics, its publication sources):
    detached with that world."""

    def __repr__(self) -> str:
        return "<the world's parts>"


class AgentTopics:
    """The publications declared for the agents of the running world (built with it, closed when it goes).

    Args:
        sim: The simulation (its API entries, agents, namespaces, publications and events).
        attached: Whether the sources are attached (a publication sink has connected since the process started).
    """

    def __init__(self, sim: Simulation, attached: Callable[[], bool]) -> None:
        self._sim = sim
        self._attached = attached
        self._owner = WorldParts()
        self._sources: list[tuple[Source, dict[str, Publisher], str | None]] = []  # (source, publishers, feature)
        self._slots: dict[tuple[str, str], tuple[Source, dict[str, Publisher], str | None]] = {}
        self._topics: dict[str, list[str]] = {}  # agent -> the topics declared for it (withdrawn on delete)
        with sim.events.owned_by(self._owner):
            self._description = DescriptionTopics(sim)

    def declare(self, agents: Iterable[str] | None = None) -> None:
        """One publication per agent (of ``agents``, default all) for every ``publish`` entry of the API table (the
        core's and the features'); an agent spawned with a namespace has its topics under it."""
        sim = self._sim
        features = sim.features
        for entry in sim.api_entries():
            if entry.direction != "publish" or entry.source is None:
                continue
            key = (entry.origin, entry.suffix)
            slot = self._slots.get(key)
            publishers: dict[str, Publisher] = slot[1] if slot is not None else {}
            for agent in (sim.entities if agents is None else agents):
                if sim.entities[agent].kind in entry.kinds and entry.source.has(sim, agent):
                    namespace = sim.entities.namespace(agent)
                    topic = f"{namespace}/{entry.name_for(agent)}" if namespace else entry.name_for(agent)
                    publishers[agent] = sim.publications.declare(Publication(
                        topic, entry.ros_type, entry.qos, entry.doc, entry.origin, agent, entry.request))
                    self._topics.setdefault(agent, []).append(topic)
            if publishers and slot is None:
                slot = (entry.source, publishers, features.entry_owner(entry))
                self._slots[key] = slot
                self._sources.append(slot)
                if self._attached():
                    self._attach(*slot)

    def attach(self) -> None:
        """Attach the sources of the agents' publications (when the first sink connects)."""
        for source, publishers, feature in self._sources:
            self._attach(source, publishers, feature)

    def _attach(self, source: Source, publishers: dict[str, Publisher], feature: str | None) -> None:
        with self._sim.events.owned_by(self._owner if feature is None else FeatureOwner(feature)):
            source.attach(self._sim, publishers)

    def add(self, robots: Iterable[str]) -> None:
        """Robots or people were added: their ``robot_description`` (under their namespace)."""
        for robot in robots:
            self._description.add(robot, self._sim.entities.namespace(robot))

    def remove(self, name: str) -> None:
        """Agent ``name`` was removed: its topics are withdrawn, its ``robot_description`` if it has one."""
        self._description.remove(name)
        for topic in self._topics.pop(name, []):
            self._sim.publications.withdraw(topic)
        for _, publishers, _ in self._sources:
            publishers.pop(name, None)

    def close(self) -> None:
        """The world goes: what its own parts subscribed is detached."""
        self._sim.events.detach(self._owner)
