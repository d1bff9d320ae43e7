"""The transport interface: how the outside world (ROS 2, ...) talks to a running simulation."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, ClassVar

if TYPE_CHECKING:
    from .sim.simulation import Simulation


class Transport(ABC):
    """Exposes a simulation's agent API. The simulation loop calls it between steps, never during one, so the
    same inputs give the same results; a transport must never block the loop longer than ``service``'s timeout."""

    name: ClassVar[str]

    @classmethod
    def unavailable(cls) -> str | None:
        """Why this transport cannot start on this machine (e.g. a library it needs is missing, and what to install),
        or None when it can. ``sigcore run`` asks before choosing its default transport; the default says None."""
        return None

    def describe(self, sim: Simulation) -> dict[str, str]:
        """Every endpoint :meth:`start` would create for ``sim`` (name -> interface type), without creating any:
        what ``sigcore api WORLD`` lists. The default: the agents' API table entries and the declared
        publications, by their names."""
        out = {entry.name_for(agent): entry.ros_type for entry in sim.api_entries() if entry.direction != "publish"
               for agent, handle in sim.agents.items() if handle.kind in entry.kinds}
        out.update({p.topic: p.full_type for p in sim.publications.declared})
        return out

    @abstractmethod
    def start(self, sim: Simulation) -> None:
        """Create every endpoint for ``sim``'s agents (from the API table) and announce readiness."""

    @abstractmethod
    def service(self, timeout: float) -> None:
        """Handle pending requests; wait at most ``timeout`` [s] (0 while running, > 0 while paused)."""

    @abstractmethod
    def stop(self) -> None:
        """Close every endpoint."""
