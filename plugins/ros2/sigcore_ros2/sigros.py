"""The sig_ros-compatible endpoints, ``<agent><suffix>``, generated from the API table."""

from __future__ import annotations

import functools
import logging
from collections.abc import Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rclpy.subscription import Subscription

from sigcore.api.call import call, finish, log_key
from sigcore.api.deferred import Deferred
from sigcore.api.table import ApiEntry
from sigcore.text import clip

from .convert import fill, ros_type, to_dict
from .qos import Qos

if TYPE_CHECKING:
    from rclpy.node import Node

    from sigcore.sim.simulation import Simulation

    from .receiver import Receiver

log = logging.getLogger("sigcore.ros2")

SHARED_NAMESPACE = "/sigcore/sigros"
"""Where the shared, per-name endpoints are: ``/sigcore/sigros/<suffix without its underscore>``."""

NOT_BY_NAME = frozenset({"SendMsgToSrv"})
"""Request types whose ``name`` field is not the entity (``_send_msg_to_srv``: the service's name)."""


@dataclass
class _Held:
    """A service request whose answer needs more steps (a :class:`Deferred` of the API)."""

    entry: ApiEntry
    agent: str
    deferred: Deferred
    srv: Any
    header: Any


class SigRosEndpoints:
    """Every ``<agent><suffix>`` subscription and service of the selected agents (their published topics are
    declared by the core: :class:`~sigcore_ros2.publications.PublicationEndpoints` creates them), and one shared
    endpoint per function whose request names its entity, ``/sigcore/sigros/<function>``, that serves every
    agent by the request's ``name`` (:meth:`shared_plan`): 35 endpoints for the core's table whatever the number
    of plain objects, instead of about 45 per object.

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
        self.node = node
        self.receiver = receiver
        self.qos = qos
        self.held: list[_Held] = []
        self.names: dict[str, str] = {}  # endpoint name -> ROS type, for tests and docs
        self.missing: set[str] = set()  # API types with no built ROS 2 type (a feature newer than the build)
        self._of: dict[str, list[tuple[str, Any]]] = {}  # agent -> (endpoint name, subscription or service)
        self._create(self.plan(sim, agents))
        self._create_shared()

    def add(self, agents: Collection[str]) -> None:
        """Create the endpoints of ``agents`` (added while running; each under its namespace,
        ``sim.entities.namespace(agent)``), as the constructor does for the world's."""
        self._create(self.plan(self.sim, agents))

    def remove(self, agents: Collection[str], why: str) -> None:
        """Destroy the endpoints of ``agents`` (deleted while running): their held and queued requests are answered
        first with ``success=false`` and ``why``."""
        gone = set(agents)
        for held in [h for h in self.held if h.agent in gone]:
            _refuse(held.srv, held.header, why)
        self.held = [h for h in self.held if h.agent not in gone]
        endpoints = [pair for agent in agents for pair in self._of.pop(agent, [])]
        if not endpoints:
            return
        released = self.receiver.retire([e for _, e in endpoints],
                                        lambda srv, _request, header: _refuse(srv, header, why))
        for name, entity in endpoints:
            self.names.pop(name, None)
            if released:
                if isinstance(entity, Subscription):
                    self.node.destroy_subscription(entity)
                else:  # once its refusals went out (one may wait for its client's response reader)
                    self.receiver.responder.then_destroy(entity, functools.partial(self.node.destroy_service, entity))

    def _create(self, plan: list[tuple[ApiEntry, str]]) -> None:
        node, receiver, qos = self.node, self.receiver, self.qos
        for entry, agent in plan:
            namespace = self.sim.entities.namespace(agent)
            name = f"{namespace}/{entry.name_for(agent)}" if namespace else entry.name_for(agent)
            try:
                ros_type(entry, "srv" if entry.direction == "service" else "msg")
            except (ImportError, AttributeError):
                if entry.ros_type not in self.missing:
                    self.missing.add(entry.ros_type)
                    log.warning("no ROS 2 type for %s (from %s): its endpoints are left out; rebuild the "
                                "interfaces: sigcore interfaces && python scripts/build_interfaces.py",
                                entry.ros_type, entry.origin)
                continue
            entity: Any
            if entry.direction == "subscribe":
                msg_type = ros_type(entry, "msg")
                entity = node.create_subscription(msg_type, name, _noop, qos.commands(name))
                receiver.add_subscription(entity, self._on_message(entry, agent))
            else:
                srv_type = ros_type(entry, "srv")
                entity = srv = node.create_service(srv_type, name, _noop)
                receiver.add_service(srv, self._on_request(entry, agent, srv))
            self._of.setdefault(agent, []).append((name, entity))
            self.names[name] = entry.ros_type

    def _create_shared(self) -> None:
        """The shared endpoints (:meth:`shared_plan`); they stay while worlds come and go."""
        for entry, name in self.shared_plan(self.sim):
            try:
                msg_type = ros_type(entry, "srv" if entry.direction == "service" else "msg")
            except (ImportError, AttributeError):
                continue  # warned about by _create, or a type no agent of this world uses
            entity: Any
            if entry.direction == "subscribe":
                entity = self.node.create_subscription(msg_type, name, _noop, self.qos.commands(name))
                self.receiver.add_subscription(entity, self._on_shared_message(entry, name))
            else:
                entity = self.node.create_service(msg_type, name, _noop)
                self.receiver.add_service(entity, self._on_shared_request(entry, name, entity))
            self.names[name] = entry.ros_type

    @staticmethod
    def shared_plan(sim: Simulation) -> list[tuple[ApiEntry, str]]:
        """``(entry, name)`` of every shared endpoint: one per subscribed or service entry whose request has a
        ``name`` field naming the entity, ``/sigcore/sigros/<suffix without its leading underscore>``; the agent
        is the request's ``name`` (required there: the shared endpoint has no agent of its own)."""
        return [(e, f"{SHARED_NAMESPACE}/{e.suffix.lstrip('_')}") for e in sim.api_entries()
                if e.direction != "publish" and e.request is not None and "name" in e.request.model_fields
                and e.ros_type not in NOT_BY_NAME]

    @staticmethod
    def plan(sim: Simulation, agents: Collection[str] | None = None) -> list[tuple[ApiEntry, str]]:
        """``(entry, agent)`` of every subscription and service (the published entries are the core's
        publications) of ``agents`` (None: of every agent)."""
        entries = [e for e in sim.api_entries() if e.direction != "publish"]
        return [(entry, agent) for agent, handle in sim.entities.items() for entry in entries
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

    def _shared_agent(self, entry: ApiEntry, fields: dict[str, Any], endpoint: str) -> tuple[str, str | None]:
        """The agent a shared endpoint's request names, and why it cannot be served (or None)."""
        agent = fields.get("name", "")
        few = ", ".join(list(self.sim.entities)[:5]) + (", ..." if len(self.sim.entities) > 5 else "")
        if not agent:
            return agent, (f"{endpoint}: 'name' must name the entity (this shared endpoint serves every agent by "
                           f"name; agents: {few or 'none'})")
        handle = self.sim.entities.get(agent)
        if handle is None:  # refused here, so that each stranger name is not an endpoint of its own in the log
            return agent, f"{endpoint}: no agent {clip(agent, 80)!r}; agents: {few or 'none'}"
        if handle.kind not in entry.kinds:
            return agent, (f"{endpoint}: '{agent}' is a {handle.kind}; {entry.suffix} is for "
                           f"{', '.join(sorted(entry.kinds))}")
        return agent, None

    def _on_shared_message(self, entry: ApiEntry, endpoint: str) -> Any:
        assert entry.request is not None
        model = entry.request

        def handle(msg: Any) -> None:
            fields = to_dict(msg, model)
            agent, why = self._shared_agent(entry, fields, endpoint)
            if why is not None:
                log.warning("%s", why, extra=log_key(endpoint, "no agent"))
                return
            call(self.sim, entry, agent, fields)  # refusals are logged (once per kind)

        return handle

    def _on_shared_request(self, entry: ApiEntry, endpoint: str, srv: Any) -> Any:
        assert entry.request is not None
        model = entry.request

        def handle(request: Any, header: Any) -> None:
            fields = to_dict(request, model)
            agent, why = self._shared_agent(entry, fields, endpoint)
            if why is not None:
                log.warning("%s", why, extra=log_key(endpoint, "no agent"))
                _refuse(srv, header, why)
                return
            result = call(self.sim, entry, agent, fields)
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
            _refuse(held.srv, held.header, why)
        self.held = []


def _refuse(srv: Any, header: Any, why: str) -> None:
    """Answer the request ``header`` of ``srv`` with ``success=false`` and ``why``."""
    srv.send_response(fill(srv.srv_type.Response(), {"success": False, "message": why}), header)


def _noop(*_: Any) -> None:
    """Placeholder callback: the receiver thread takes messages itself, never through an executor."""
