"""The sig_ros-compatible endpoints, ``<agent><suffix>``, generated from the API table."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from sigcore.agent.events import CollisionEvent, Message
from sigcore.api.call import call, finish
from sigcore.api.deferred import Deferred
from sigcore.api.table import ApiEntry
from sigcore.sim.lidar import Scan

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
    """Every ``<agent><suffix>`` topic and service of the world's agents.

    Args:
        sim: The simulation.
        node: The node that owns the endpoints.
        receiver: Where subscriptions and services are registered.
        qos: QoS profiles.
        scans: Publishes the ``<robot>_scan`` LaserScans (set by the standard endpoints, which build them).
    """

    def __init__(self, sim: Simulation, node: Node, receiver: Receiver, qos: Qos) -> None:
        self.sim = sim
        self.held: list[_Held] = []
        self.collision: dict[str, Any] = {}
        self.recv: dict[str, Any] = {}
        self.scan: dict[str, Any] = {}
        self.names: dict[str, str] = {}  # endpoint name -> ROS type, for tests and docs
        self.missing: set[str] = set()  # API types with no built ROS 2 type (a feature newer than the build)
        robots_with_lidar = {lidar.robot for lidar in sim.lidars}
        entries = sim.api_entries()
        for agent, handle in sim.agents.items():
            for entry in entries:
                if handle.kind not in entry.kinds:
                    continue
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
                if entry.direction == "publish":
                    if entry.suffix == "_scan" and agent not in robots_with_lidar:
                        continue
                    msg_type = ros_type(entry, "msg")
                    profile = qos.sensor(name) if entry.suffix == "_scan" else qos.events(name)
                    pub = node.create_publisher(msg_type, name, profile)
                    {"_onCollisionMsg": self.collision, "_onRecvMsg": self.recv, "_scan": self.scan}.get(
                        entry.suffix, {})[agent] = pub
                elif entry.direction == "subscribe":
                    msg_type = ros_type(entry, "msg")
                    sub = node.create_subscription(msg_type, name, _noop, qos.commands(name))
                    receiver.add_subscription(sub, self._on_message(entry, agent))
                else:
                    srv_type = ros_type(entry, "srv")
                    srv = node.create_service(srv_type, name, _noop)
                    receiver.add_service(srv, self._on_request(entry, agent, srv))
                self.names[name] = entry.ros_type
        sim.collision_observers.append(self._collided)
        sim.message_observers.append(self._received)

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

    # ------------------------------------------------------------------ outgoing
    def _collided(self, event: CollisionEvent) -> None:
        pub = self.collision.get(event.agent)
        if pub is not None:
            msg = pub.msg_type()
            msg.name, msg.part = event.other, event.part
            pub.publish(msg)

    def _received(self, message: Message) -> None:
        pub = self.recv.get(message.to)
        if pub is not None:
            msg = pub.msg_type()
            msg.sender, msg.content = message.sender, message.content
            pub.publish(msg)

    def publish_scan(self, scan: Scan, msg: Any) -> None:
        """Publish a built LaserScan on ``<robot>_scan``."""
        pub = self.scan.get(scan.robot)
        if pub is not None:
            pub.publish(msg)


def _noop(*_: Any) -> None:
    """Placeholder callback: the receiver thread takes messages itself, never through an executor."""
