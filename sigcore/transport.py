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

    @abstractmethod
    def start(self, sim: Simulation) -> None:
        """Create every endpoint for ``sim``'s agents (from the API table) and announce readiness."""

    @abstractmethod
    def service(self, timeout: float) -> None:
        """Handle pending requests; wait at most ``timeout`` [s] (0 while running, > 0 while paused)."""

    @abstractmethod
    def stop(self) -> None:
        """Close every endpoint."""
