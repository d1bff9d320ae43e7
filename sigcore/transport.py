"""The transport interface: how the outside world (ROS 2, ...) talks to a running simulation."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Literal

from .errors import TransportError
from .world.names import full_name_problem

if TYPE_CHECKING:
    from .sim.simulation import Simulation
    from .world.exceptions import WorldIssue


@dataclass(frozen=True)
class Endpoint:
    """One endpoint a transport would create, and what in the world brought its name in.

    Attributes:
        name: The name as created: absolute (``/robot_000/odom``) or relative to the node's namespace ``/``
            (``robot_000_setWheel``).
        type: The interface type, e.g. ``sensor_msgs/msg/LaserScan``.
        kind: ``topic``, ``service`` or ``action`` (ROS keeps each kind's names apart).
        what: Who uses the name, for messages, e.g. ``"the LaserScan of <lidar name='odom'> of robot 'r'"``.
        agent: The agent whose element brought the name in; None for a plugin's or the transport's own.
        attribute: Where in that element: an attribute (``name``) or a child element's key (``lidar:odom``,
            ``drive``, see :meth:`sigcore.world.World.location`); None: the element itself.
        element: The XML element named in messages (``lidar``, ``drive``); None: the agent's own.
        plugin: The ``<plugin>`` that brought it in (a feature's publication), if not an agent.
        shared: A topic several publishers share when they publish one type (``/tf``).
    """

    name: str
    type: str
    kind: Literal["topic", "service", "action"]
    what: str
    agent: str | None = None
    attribute: str | None = None
    element: str | None = None
    plugin: str | None = None
    shared: bool = False

    @property
    def full_name(self) -> str:
        """The name resolved in the node namespace ``/``."""
        return self.name if self.name.startswith("/") else "/" + self.name


class Transport(ABC):
    """Exposes a simulation's agent API. The simulation loop calls it between steps, never during one, so the
    same inputs give the same results; a transport must never block the loop longer than ``service``'s timeout."""

    name: ClassVar[str]

    @classmethod
    def unavailable(cls) -> str | None:
        """Why this transport cannot start on this machine (e.g. a library it needs is missing, and what to install),
        or None when it can. ``sigcore run`` asks before choosing its default transport; the default says None."""
        return None

    def plan(self, sim: Simulation) -> list[Endpoint]:
        """Every endpoint :meth:`start` would create for ``sim``, with who asked for it, without creating any.
        The default: the agents' API table entries and the declared publications."""
        out = [Endpoint(entry.name_for(agent), entry.ros_type, "service" if entry.direction == "service" else "topic",
                        f"'{entry.suffix}' of {handle.kind} '{agent}'", agent)
               for entry in sim.api_entries() if entry.direction != "publish"
               for agent, handle in sim.entities.items() if handle.kind in entry.kinds]
        return out + publication_endpoints(sim)

    def describe(self, sim: Simulation) -> dict[str, str]:
        """Every endpoint :meth:`start` would create for ``sim`` (name -> interface type), without creating any:
        what ``sigcore api WORLD`` lists; derived from :meth:`plan`."""
        return {e.name: e.type for e in self.plan(sim)}

    def name_problem(self, name: str) -> str | None:
        """Why the full name ``name`` cannot be created by this transport, or None; default: the core's ROS rule
        (:func:`sigcore.world.names.full_name_problem`)."""
        return full_name_problem(name)

    def check(self, sim: Simulation) -> list[WorldIssue]:
        """Every endpoint of :meth:`plan` that cannot be created (an invalid name, a name used twice), located at
        the world element that brought it in; empty when :meth:`start` can create them all."""
        from .world.names import plan_issues

        return plan_issues(sim.world, self.plan(sim), self.name, self.name_problem)

    def configure(self, args: list[str]) -> None:
        """Take the transport's own command-line arguments (``sigcore run WORLD ... --ros-args ARGS``, unparsed),
        before :meth:`plan` and :meth:`start`; the default takes none.

        Raises:
            TransportError: this transport takes no arguments, or one of ``args`` is wrong (naming it and what is
                valid).
        """
        raise TransportError(f"transport '{self.name}' does not support transport arguments (--ros-args)")

    def matched(self, topic: str) -> tuple[int, str]:
        """How many peers are matched with ``topic`` (a topic name of :meth:`plan`) now, after :meth:`start`, and
        what they are: ``(n, "subscriber")`` for a topic the simulation publishes, ``(n, "publisher")`` for one it
        subscribes to. ``sigcore run --wait-for`` polls it while the simulation waits to start.

        Raises:
            TransportError: this transport cannot tell (the default), or ``topic`` is not one of its topics.
        """
        raise TransportError(f"transport '{self.name}' does not support counting the peers of a topic (--wait-for)")

    @abstractmethod
    def start(self, sim: Simulation) -> None:
        """Create every endpoint for ``sim``'s agents (from the API table) and announce readiness."""

    @abstractmethod
    def service(self, timeout: float) -> None:
        """Handle pending requests; wait at most ``timeout`` [s] (0 while running, > 0 while paused)."""

    @abstractmethod
    def stop(self) -> None:
        """Close every endpoint."""


def publication_endpoints(sim: Simulation, agents: bool | Collection[str] = True) -> list[Endpoint]:
    """The declared publications of ``sim`` (the core's and the features') as endpoints; ``agents``: also the
    per-agent ones (True: of every agent; a collection: of these agents only)."""
    out = []
    for p in sim.publications.declared:
        if p.agent and (not agents or (agents is not True and p.agent not in agents)):
            continue
        plugin = p.origin if sim.world.plugin(p.origin) is not None else None
        who = f"{p.agent}'s '{p.topic}'" if p.agent else f"the publication '{p.topic}' of {p.origin}"
        out.append(Endpoint(p.topic, p.full_type, "topic", who, p.agent or None, plugin=None if p.agent else plugin,
                            shared=p.qos == "tf"))
    return out
