"""A model that spawn requests may name as ``model://NAME``: :class:`Spawnable` (``get_spawnables`` lists them)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Spawnable:
    """A model that ``SpawnRequest.uri`` may name as ``model://NAME`` (``get_spawnables`` lists them).

    Attributes:
        name: The ``NAME`` of ``model://NAME``.
        description: What it is, for people.
        element: The world-format element that defines it (``<robot urdf="sigbot.urdf">...</robot>``), with
            relative paths starting at ``base``.
        base: Folder that relative paths in ``element`` start from.
        origin: Who offers it (``worlds/models`` or a plugin's name).
        bounds: Its axis-aligned bounds around its origin, ``(min xyz, max xyz)`` [m], if known.
    """

    name: str
    description: str
    element: str
    base: str
    origin: str = "worlds/models"
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]] | None = field(default=None)

    @property
    def uri(self) -> str:
        """``model://NAME``."""
        return f"model://{self.name}"
