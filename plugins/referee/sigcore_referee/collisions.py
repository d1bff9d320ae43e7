"""Clean-up rule for collisions: one penalty per contact episode of a robot with furniture, a wall or the floor."""

from __future__ import annotations

from dataclasses import dataclass

from sigcore.agent.events import CollisionEvent
from sigcore.backend import GROUND
from sigcore.sim.simulation import Simulation
from sigcore.world.models import Entity, Robot

from .config import RefereeConfig
from .items import Award


@dataclass
class Episode:
    """A contact episode between one robot and one entity (or the ground).

    Attributes:
        robot: The robot.
        other: The entity touched (``"ground"`` for the floor).
        start: When it began [s].
        last_seen: When the contact was last present [s].
    """

    robot: str
    other: str
    start: float
    last_seen: float


def default_floor_parts(sim: Simulation, robot: str) -> frozenset[str]:
    """Parts of ``robot`` that stand on the floor: its wheels and casters, as the core's contact events define
    them (``sim.entities.rolling_parts``; their floor contacts are no collision events)."""
    return sim.entities.rolling_parts(robot)


class CollisionRule:
    """Opens an episode (and awards the penalty) on the first contact, closes it after ``debounce`` seconds
    without contact. Contacts start episodes as they happen (a collision observer, every step); whether they go
    on is sampled at the referee's rate."""

    def __init__(self, sim: Simulation, config: RefereeConfig, robots: list[str], award: Award) -> None:
        self.sim, self.config, self.award = sim, config, award
        self.robots = set(robots)
        self.floor_ok = {r: frozenset(config.floor_parts) if config.floor_parts is not None
                         else default_floor_parts(sim, r) for r in robots}
        tags = set(config.collision_tags)
        self.penalised = {a.name: sorted(tags & set(a.tags)) for a in sim.world.entities if tags & set(a.tags)}
        self.episodes: dict[tuple[str, str], Episode] = {}
        self.count = 0

    def reset(self) -> None:
        """Close every open episode."""
        self.episodes.clear()

    def add(self, entity: Entity) -> None:
        """Watch entity ``entity``, spawned while running: penalise touching it if it has a collision tag, and
        watch it if it is a robot and the rules watch every robot (``robots`` not given)."""
        tags = set(self.config.collision_tags) & set(entity.tags)
        if tags:
            self.penalised[entity.name] = sorted(tags)
        if isinstance(entity, Robot) and self.config.robots is None:
            self.robots.add(entity.name)
            self.floor_ok[entity.name] = frozenset(self.config.floor_parts) if self.config.floor_parts is not None \
                else default_floor_parts(self.sim, entity.name)

    def remove(self, name: str) -> None:
        """Forget entity ``name`` (deleted): its open episodes end; the penalties already given stay."""
        self.penalised.pop(name, None)
        self.robots.discard(name)
        self.floor_ok.pop(name, None)
        self.episodes = {k: e for k, e in self.episodes.items() if name not in k}

    def counts(self, robot: str, part: str, other: str) -> bool:
        """Whether contact of ``robot``'s ``part`` with ``other`` is a collision the rules penalise."""
        if other == GROUND:
            return self.config.floor and part not in self.floor_ok[robot]
        return other in self.penalised

    def on_collision(self, event: CollisionEvent) -> None:
        """A new contact (collision observer)."""
        if event.agent not in self.robots or not self.counts(event.agent, event.part, event.other):
            return
        key = (event.agent, event.other)
        episode = self.episodes.get(key)
        if episode is not None:
            episode.last_seen = event.time
            return
        self.episodes[key] = Episode(event.agent, event.other, event.time, event.time)
        self.count += 1
        if event.other == GROUND:
            what = f"{event.agent} touched the floor with {event.part}"
        else:
            what = f"{event.agent} hit {event.other} ({' '.join(self.penalised[event.other])}) with {event.part}"
        self.award("collision", what, self.config.collision)

    def look(self, now: float) -> None:
        """Extend episodes whose contact goes on; close those without contact for ``debounce`` seconds."""
        if not self.episodes:
            return
        touching = {(robot, other) for robot, part, other in self.sim.contact_triples()
                    if (robot, other) in self.episodes and self.counts(robot, part, other)}
        for key, episode in list(self.episodes.items()):
            if key in touching:
                episode.last_seen = now
            elif now - episode.last_seen >= self.config.debounce - 1e-9:
                del self.episodes[key]
