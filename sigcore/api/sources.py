"""Where the values of the API table's ``publish`` entries come from (the core's event streams).

Each source attaches to the simulation when the first publication sink connects (so a run without a transport
computes nothing for them) and pushes one value per event through the agent's publisher. A source also says which
agents have the endpoint (``<robot>_scan`` only for robots with a ``<lidar>``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..agent.events import CollisionEvent, Message
    from ..publish import Publisher
    from ..sim.lidar import Scan
    from ..sim.simulation import Simulation


class Source(ABC):
    """The values of one ``publish`` entry, for every agent that has it."""

    def has(self, sim: Simulation, agent: str) -> bool:
        """Whether ``agent`` has this endpoint (default: every agent of the entry's kinds)."""
        return True

    @abstractmethod
    def attach(self, sim: Simulation, publishers: dict[str, Publisher]) -> None:
        """Start pushing values through ``publishers[agent]``."""


class ReceivedMessages(Source):
    """``<agent>_onRecvMsg``: every text message delivered to the agent."""

    def attach(self, sim: Simulation, publishers: dict[str, Publisher]) -> None:
        def on_message(message: Message) -> None:
            pub = publishers.get(message.to)
            if pub is not None:
                pub.publish({"sender": message.sender, "content": message.content})

        sim.events.subscribe("message", on_message)


class Collisions(Source):
    """``<agent>_onCollisionMsg``: every collision event of the agent (see ``docs/api.md``)."""

    def attach(self, sim: Simulation, publishers: dict[str, Publisher]) -> None:
        def on_collision(event: CollisionEvent) -> None:
            pub = publishers.get(event.agent)
            if pub is not None:
                pub.publish({"name": event.other, "part": event.part})

        sim.events.subscribe("collision", on_collision)


class Scans(Source):
    """``<robot>_scan``: every scan of the robot's lidars, in the lidar link's TF frame."""

    def has(self, sim: Simulation, agent: str) -> bool:
        return any(lidar.robot == agent for lidar in sim.entities.lidars)

    def attach(self, sim: Simulation, publishers: dict[str, Publisher]) -> None:
        dt_ns = round(sim.dt * 1e9)

        def on_scan(scan: Scan) -> None:
            pub = publishers.get(scan.robot)
            if pub is not None:
                stamp = round(scan.stamp / sim.dt) * dt_ns
                pub.publish(scan.fields(sim.frames.name(scan.robot, scan.frame), stamp), stamp)

        sim.events.subscribe("scan", on_scan)
