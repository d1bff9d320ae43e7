"""What each entity is: its category, description and tags (one owner), and the world's named poses.

The world file gives the initial values (``tags`` and ``description`` attributes; the category follows from the
element); ``EntityInfos.set`` (the simulation_interfaces service ``set_entity_info``) changes them while running and
``Simulation.reset`` puts the world file's back. Features that read the world model directly (the referee) keep the
tags they read at start.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal, get_args

from ..agent.exceptions import ApiError
from ..text import quote
from ..world.models import Entity, Human, NamedPose, Object, Robot, check_description, check_tags

Category = Literal["object", "robot", "human", "dynamic_object", "static_object"]
"""An entity's major category, as in simulation_interfaces' ``EntityCategory`` (``CATEGORY_<upper case>``)."""

CATEGORIES: tuple[Category, ...] = get_args(Category)


def category_of(entity: Entity) -> Category:
    """The category an entity of the world file starts with: a robot ``robot``, a human ``human`` (static or not),
    a static object ``static_object``, any other object ``object`` (generic: a can or a ball, not the moving
    obstacle that ``dynamic_object`` stands for)."""
    if isinstance(entity, Robot):
        return "robot"
    if isinstance(entity, Human):
        return "human"
    return "static_object" if isinstance(entity, Object) and entity.static else "object"


@dataclass(frozen=True)
class EntityInfo:
    """What an entity is.

    Attributes:
        category: Its major category.
        description: Human-readable text; empty when the world file gives none.
        tags: Labels (each one word), in the world file's order.
    """

    category: Category
    description: str
    tags: tuple[str, ...]


class EntityInfos:
    """The category, description and tags of every entity (robots, objects, humans).

    Args:
        entities: The world's entities.
    """

    def __init__(self, entities: Iterable[Entity]) -> None:
        self._initial = {e.name: EntityInfo(category_of(e), e.description, tuple(e.tags)) for e in entities}
        self._infos = dict(self._initial)

    @property
    def names(self) -> list[str]:
        """Every entity, in the world file's order."""
        return list(self._infos)

    def get(self, entity: str) -> EntityInfo:
        """The information of ``entity`` now.

        Raises:
            ApiError: no such entity (the message lists them).
        """
        info = self._infos.get(entity)
        if info is None:
            raise ApiError(f"no entity {quote(entity)}; entities: {', '.join(self._infos)}")
        return info

    def set(self, entity: str, category: str, description: str, tags: Iterable[str]) -> EntityInfo:
        """Replace all three of ``entity``'s category, description and tags.

        Raises:
            ApiError: no such entity, a category not in :data:`CATEGORIES`, a description longer than
                ``MAX_DESCRIPTION``, or a tag that is empty, holds whitespace or control characters, is longer
                than ``MAX_TAG_LENGTH``, or more than ``MAX_TAGS`` tags; nothing is changed then.
        """
        self.get(entity)
        if category not in CATEGORIES:
            raise ApiError(f"category {quote(str(category))} is not one of {', '.join(CATEGORIES)}")
        tag_tuple = tuple(tags)
        try:
            check_tags(tag_tuple)
            check_description(description)
        except ValueError as e:
            raise ApiError(str(e)) from None
        info = EntityInfo(category, description, tag_tuple)  # type: ignore[arg-type]  # checked above
        self._infos[entity] = info
        return info

    def with_tags(self, tags: Iterable[str], match_all: bool = False) -> list[str]:
        """The entities that carry any (``match_all``: every one) of ``tags``, in the world file's order; every
        entity when ``tags`` is empty."""
        wanted = set(tags)
        if not wanted:
            return self.names
        if match_all:
            return [n for n, i in self._infos.items() if wanted <= set(i.tags)]
        return [n for n, i in self._infos.items() if wanted & set(i.tags)]

    def in_categories(self, categories: Iterable[str]) -> list[str]:
        """The entities whose category is one of ``categories``, in the world file's order."""
        wanted = set(categories)
        return [n for n, i in self._infos.items() if i.category in wanted]

    def add(self, entities: Iterable[Entity]) -> None:
        """Entities spawned while running: their information as given (what a reset restores for them)."""
        for e in entities:
            self._initial[e.name] = self._infos[e.name] = EntityInfo(category_of(e), e.description, tuple(e.tags))

    def remove(self, names: Iterable[str]) -> None:
        """Entities deleted while running."""
        for name in names:
            self._initial.pop(name, None)
            self._infos.pop(name, None)

    def reset(self) -> None:
        """Back to the world file's values (spawned entities: their values as spawned)."""
        self._infos = dict(self._initial)


def named_poses_with_tags(poses: Iterable[NamedPose], tags: Iterable[str], match_all: bool = False) -> list[NamedPose]:
    """The named poses that carry any (``match_all``: every one) of ``tags``; all of them when ``tags`` is empty."""
    wanted = set(tags)
    if not wanted:
        return list(poses)
    return [p for p in poses if (wanted <= set(p.tags) if match_all else wanted & set(p.tags))]
