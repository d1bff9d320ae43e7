"""Events delivered to controllers and transports."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class CollisionEvent:
    """The start of a contact episode between one of an agent's parts and another entity (``sigcore.sim.contacts``).

    Attributes:
        agent: The agent receiving the event.
        part: The agent's own part in contact.
        other: The other entity (``"ground"`` for the ground plane).
        time: Simulation time of the step that produced it [s].
    """

    agent: str
    part: str
    other: str
    time: float


@dataclass(frozen=True, slots=True)
class Message:
    """A text message between agents (or from a service or a transport).

    Attributes:
        sender: Name of the sending agent, service or transport client.
        to: Receiving agent.
        content: The text.
        time: Simulation time when it was sent [s].
    """

    sender: str
    to: str
    content: str
    time: float
