"""The feature interface: world-level add-ons enabled with ``<plugin name=...>`` (SLAM, IK, referee...)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, ClassVar

if TYPE_CHECKING:
    from .api.table import ApiEntry
    from .sim.simulation import Simulation


class Feature(ABC):
    """A feature of one simulation, configured by the attributes of its ``<plugin>`` element."""

    name: ClassVar[str]

    @classmethod
    def api_entries(cls) -> list[ApiEntry]:
        """Endpoints this feature adds to every agent of the listed kinds (e.g. ``_ik`` for robots). Their types
        must be in an interface package: bundled features' types are generated into ``sigcore_msgs``."""
        return []

    @abstractmethod
    def __init__(self, sim: Simulation, config: dict[str, str]) -> None:
        """Validate ``config`` (raise ``ValueError`` naming the attribute and what is valid) and attach to ``sim``
        (e.g. with ``sim.add_step_observer``)."""

    def summary(self) -> dict[str, object]:
        """Figures to print at the end of a run (e.g. a score)."""
        return {}

    def report(self) -> list[str]:
        """Lines printed as they are after the summaries at the end of a run (e.g. a score table); none by default."""
        return []

    def outcome(self) -> bool | None:
        """Whether the world's task succeeded, for the exit code of ``sigcore run`` (1 if any feature says False);
        ``None``: no verdict (the default, or the task has not ended)."""
        return None

    def reset(self) -> None:
        """Called by :meth:`Simulation.reset` after the backend's state was restored; forget per-run state."""
        return None
