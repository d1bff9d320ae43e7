"""The sig_ros-compatible endpoints, ``<agent><suffix>``, generated from the API table."""

from __future__ import annotations

import logging
from collections.abc import Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from sigcore.api.call import call, finish
from sigcore.api.deferred import Deferred
from sigcore.api.table import ApiEntry

from .convert import fill, ros_type, to_dict
from .qos import Qos

if TYPE_CHECKING:
    from rclpy.node import Node

    from sigcore.sim.simulation import Simulation

    from .receiver import Receiver

log = logging.getLogger("sigcore.ros2")


@dataclass
class _Held:
    """A service request whose answer needs more steps (a :class:`Deferred` of the API)."""

    entry: ApiEntry
    agent: str
    deferred: Deferred
    srv: Any
    header: Any


class SigRosEndpoints:
    """Every ``<agent><suffix>`` subscription and service of the world's agents (their published topics are
    declared by the core: :class:`~sigcore_ros2.publications.PublicationEndpoints` creates them).

    Args:
        sim: The simulation.
        node: The node that owns the endpoints.
        receiver: Where subscriptions and services are registered.
        qos: QoS profiles.
        agents: The agents that get endpoints (``sigros_agents``); None: every agent.
    """

    def __init__(self, sim: Simulation, node: Node, receiver: Receiver, qos: Qos,
                 agents: Collection[str] | None = None) -> None:
        self.sim = sim
        self.held: list[_Held] = []
        self.names: dict[str, str] = {}  # endpoint name -> ROS type, for tests and docs
        self.missing: set[str] = set()  # API types with no built ROS 2 type (a feature newer than the build)
        for entry, agent in self.plan(sim, agents):
            name = entry.name_for(agent)
            try:
                ros_type(entry, "srv" if entry.direction == "service" else "msg")
            except (ImportError, AttributeError):
                if entry.ros_type not in self.missing:
                    self.missing.add(entry.ros_type)
                    log.warning("no ROS 2 type for %s (from %s): its endpoints are left out; rebuild the "
                                "interfaces: sigcore interfaces && python scripts/build_interfaces.py",
                                entry.ros_type, entry.origin)
                continue
            if entry.direction == "subscribe":
                msg_type = ros_type(entry, "msg")
                sub = node.create_subscription(msg_type, name, _noop, qos.commands(name))
                receiver.add_subscription(sub, self._on_message(entry, agent))
            else:
                srv_type = ros_type(entry, "srv")
                srv = node.create_service(srv_type, name, _noop)
                receiver.add_service(srv, self._on_request(entry, agent, srv))
            self.names[name] = entry.ros_type

    @staticmethod
    def plan(sim: Simulation, agents: Collection[str] | None = None) -> list[tuple[ApiEntry, str]]:
        """``(entry, agent)`` of every subscription and service (the published entries are the core's
        publications) of ``agents`` (None: of every agent)."""
        entries = [e for e in sim.api_entries() if e.direction != "publish"]
        return [(entry, agent) for agent, handle in sim.agents.items() for entry in entries
                if handle.kind in entry.kinds and (agents is None or agent in agents)]

    # ------------------------------------------------------------------ incoming
    def _on_message(self, entry: ApiEntry, agent: str) -> Any:
        assert entry.request is not None
        model = entry.request

        def handle(msg: Any) -> None:
            call(self.sim, entry, agent, to_dict(msg, model))  # refusals are logged (once per kind)

        return handle

    def _on_request(self, entry: ApiEntry, agent: str, srv: Any) -> Any:
        assert entry.request is not None
        model = entry.request

        def handle(request: Any, header: Any) -> None:
            result = call(self.sim, entry, agent, to_dict(request, model))
            if isinstance(result, Deferred):
                self.held.append(_Held(entry, agent, result, srv, header))
                return
            srv.send_response(fill(srv.srv_type.Response(), result), header)

        return handle

    def poll_held(self) -> None:
        """Answer held requests that are done (after a step)."""
        still = []
        for held in self.held:
            result = finish(self.sim, held.entry, held.agent, held.deferred)
            if result is None:
                still.append(held)
            else:
                held.srv.send_response(fill(held.srv.srv_type.Response(), result), held.header)
        self.held = still

    def refuse_held(self, why: str) -> None:
        """Answer every held request with a refusal (the simulation is stopping or resetting)."""
        for held in self.held:
            held.srv.send_response(fill(held.srv.srv_type.Response(), {"success": False, "message": why}),
                                   held.header)
        self.held = []


def _noop(*_: Any) -> None:
    """Placeholder callback: the receiver thread takes messages itself, never through an executor."""
