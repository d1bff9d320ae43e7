"""What the simulation tells of entities and worlds that come and go while it runs (the ``entities`` and ``world``
events of ``sim.events``). Spawn requests, their resolution and refusals are ``sigcore.world.resources``; spawnables
are ``sigcore.world.models.Spawnable`` (found by ``sigcore.world.spawnables``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..world.models import World


@dataclass(frozen=True)
class EntityChange:
    """Entities added or removed while running, in the order they were (the ``entities`` event of ``sim.events``,
    one per spawn or delete).

    Attributes:
        added: Names of the entities added (each is in ``sim.entities``, ``sim.world``, the backend, the scene...).
        removed: Names of the entities removed (gone from all of them).
    """

    added: tuple[str, ...] = ()
    removed: tuple[str, ...] = ()


@dataclass(frozen=True)
class WorldChange:
    """A world is about to be unloaded, or was just loaded (the ``world`` event of ``sim.events``).

    Attributes:
        kind: ``unloading``: the old world is still complete (its agents, entities, publications), and everything of
            it goes right after the observers return; ``loaded``: the new world is complete, paused at time 0 (its
            step count starts again at 0; ``sim.worlds.elapsed_steps`` goes on).
        world: The world unloaded or loaded.
    """

    kind: Literal["unloading", "loaded"]
    world: World
