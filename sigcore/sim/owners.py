"""Owners of entities' parts (``_setOwner``): informational, nothing in the physics depends on them."""

from __future__ import annotations

from collections.abc import Collection


class Owners:
    """``(entity, part) -> owner`` as set through the API; cleared by a reset."""

    def __init__(self) -> None:
        self._owner: dict[tuple[str, str], str] = {}

    def set(self, entity: str, part: str, owner: str) -> None:
        """Record ``owner`` as the owner of ``entity``'s ``part``."""
        self._owner[(entity, part)] = owner

    def get(self, entity: str, part: str = "main") -> str | None:
        """The owner of ``entity``'s ``part``, or None."""
        return self._owner.get((entity, part))

    def forget(self, entities: Collection[str]) -> None:
        """Forget the owners of parts of ``entities`` and those that ``entities`` were (deleted while running)."""
        self._owner = {k: v for k, v in self._owner.items() if k[0] not in entities and v not in entities}

    def clear(self) -> None:
        """Forget every owner (a reset)."""
        self._owner.clear()
