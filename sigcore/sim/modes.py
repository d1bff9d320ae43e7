"""Gravity, dynamics and collision modes of every entity: one owner, which tells the backend of each change.

The backend realises a mode in its engine (a weld, a mask, zero mass) but is never asked for it: this table is the
answer to every query (``_setDynamicsMode`` and friends, the ROS 2 entity state, IK) and is restored, with the
backend's state, by a reset.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from ..backend import Backend
    from ..world.models import Human, Object, Robot

Mode = Literal["gravity", "dynamics", "collision"]
MODES: tuple[Mode, ...] = ("gravity", "dynamics", "collision")


class Modes:
    """The modes of every entity.

    Args:
        backend: Told of every change.
        entities: The world's entities (a ``static`` object starts with dynamics off).
    """

    def __init__(self, backend: Backend, entities: Iterable[Robot | Object | Human]) -> None:
        self._backend = backend
        self._initial = {e.name: {"gravity": True, "dynamics": not getattr(e, "static", False), "collision": True}
                         for e in entities}
        self._modes = {name: dict(m) for name, m in self._initial.items()}

    def get(self, entity: str, mode: Mode) -> bool:
        """Whether ``mode`` is on for ``entity``."""
        return self._modes[entity][mode]

    def of(self, entity: str) -> dict[str, bool]:
        """A copy of every mode of ``entity``."""
        return dict(self._modes[entity])

    def set(self, entity: str, mode: Mode, enabled: bool) -> None:
        """Switch ``mode`` for ``entity`` in the backend, then record it (not recorded if the backend refuses).

        Raises:
            ValueError: an unknown mode (names the valid ones).
        """
        if mode not in MODES:
            raise ValueError(f"no mode '{mode}'; modes: {', '.join(MODES)}")
        setter = {"gravity": self._backend.set_gravity_mode, "dynamics": self._backend.set_dynamics_mode,
                  "collision": self._backend.set_collision_mode}[mode]
        setter(entity, enabled)
        self._modes[entity][mode] = bool(enabled)

    def add(self, entities: Iterable[Robot | Object | Human]) -> None:
        """Entities spawned while running, with the modes their model gives (what a reset restores for them)."""
        for e in entities:
            self._initial[e.name] = {"gravity": True, "dynamics": not getattr(e, "static", False), "collision": True}
            self._modes[e.name] = dict(self._initial[e.name])

    def remove(self, names: Iterable[str]) -> None:
        """Entities deleted while running."""
        for name in names:
            self._initial.pop(name, None)
            self._modes.pop(name, None)

    def reset(self) -> None:
        """Back to the world file's modes (the backend's reset restores its side)."""
        self._modes = {name: dict(m) for name, m in self._initial.items()}
