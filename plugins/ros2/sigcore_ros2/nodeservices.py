"""The nodes' own services (``list_parameters``, ``get_parameters``, ``set_parameters``, ``get_type_description``...).

rclpy creates them with every node, but they answer only if something takes their requests. The main node's are
taken by the :class:`~sigcore_ros2.receiver.Receiver` and answered on the simulation thread, between steps, like every
other request (so a parameter can never change anything under a running step); the action node's are spun by its
executor. Either way their callbacks are guarded: a malformed request (a parameter type outside ``ParameterType``,
an empty name) gets a refusal naming what was wrong, and an exception inside rclpy becomes a refusal and one log
record instead of ending the thread that serves them.

The main node's ``use_sim_time`` is true and read-only: sigcore is the source of simulated time (it publishes
``/clock``), every stamp it publishes is simulated time, and its node clock is set to the simulation's time before
each of these requests (it does not subscribe to its own ``/clock``).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from typing import Any

from rcl_interfaces.msg import ParameterType, SetParametersResult
from rcl_interfaces.srv import SetParameters, SetParametersAtomically
from rclpy.parameter import Parameter
from type_description_interfaces.srv import GetTypeDescription

from sigcore.api.call import log_key
from sigcore.text import clip, quote

log = logging.getLogger("sigcore.ros2")

USE_SIM_TIME = "use_sim_time"

BUILTIN = ("describe_parameters", "get_parameters", "get_parameter_types", "list_parameters", "set_parameters",
           "set_parameters_atomically", "get_type_description")
"""The services rclpy gives every node (``/<node>/<name>``)."""

_TYPES = {getattr(ParameterType, n): n.removeprefix("PARAMETER_").lower() for n in dir(ParameterType)
          if n.startswith("PARAMETER_")}
VALID_TYPES = ", ".join(f"{v} {n}" for v, n in sorted(_TYPES.items()))
"""The ParameterType values, for refusals."""


_HASH = re.compile(r"RIHS01_[0-9a-f]{64}")


def sim_time_overrides() -> list[Parameter]:
    """The main node's ``parameter_overrides``: ``use_sim_time`` true."""
    return [Parameter(USE_SIM_TIME, value=True)]


def builtin_services(node: Any) -> list[Any]:
    """The node's own services (created with the node, named ``<node>/<name>``), in creation order."""
    own = {f"{node.get_name()}/{name}" for name in BUILTIN}
    return [srv for srv in node.services if srv.srv_name in own]


def full_name(node: Any, srv: Any) -> str:
    """``/<namespace>/<node>/<name>`` of one of the node's own services."""
    return f"{node.get_fully_qualified_name()}/{srv.srv_name.rsplit('/', 1)[-1]}"


def make_sim_time_read_only(node: Any, why: str) -> None:
    """Refuse every change of ``use_sim_time`` and stop the node's clock from listening to ``/clock``.

    rclpy's time source subscribed to ``/clock`` when the node was created with ``use_sim_time`` true; sigcore
    publishes that topic itself and sets its node clock from the simulation instead (:class:`NodeServices`).

    Args:
        node: The node.
        why: The reason given in refusals.
    """
    for sub in list(node.subscriptions):
        if sub.topic_name == "/clock":
            node.destroy_subscription(sub)
    reason = f"use_sim_time is read-only on {node.get_name()}: {why}"

    def refuse(params: list[Parameter]) -> SetParametersResult:
        if any(p.name == USE_SIM_TIME for p in params):
            return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(refuse)


def _problem(p: Any) -> str | None:
    """What is wrong with one rcl_interfaces/Parameter of a set request, or None."""
    if not p.name:
        return "a parameter name cannot be empty"
    if p.value.type not in _TYPES:
        return f"parameter {quote(p.name)}: value type {p.value.type} is not a ParameterType; valid: {VALID_TYPES}"
    return None


def guard(srv: Any, name: str, on_call: Callable[[], None] | None = None) -> Callable[[Any, Any], Any]:
    """A safe version of ``srv.callback(request, response) -> response``: malformed set requests are refused,
    exceptions become refusals (logged once per endpoint and kind), nothing raises.

    Args:
        srv: An rclpy service of :data:`BUILTIN`.
        name: Its full name (for the log).
        on_call: Called before each request (e.g. to set the node's clock).
    """
    original = srv.callback

    def refused(reason: str) -> SetParametersResult:
        return SetParametersResult(successful=False, reason=reason)

    def call(request: Any, response: Any) -> Any:
        if on_call is not None:
            on_call()
        try:
            if srv.srv_type is SetParameters:
                problems = [_problem(p) for p in request.parameters]
                if any(problems):
                    good = [p for p, why in zip(request.parameters, problems, strict=True) if why is None]
                    answered = iter(original(SetParameters.Request(parameters=good), response).results
                                    if good else [])
                    response.results = [refused(why) if why else next(answered) for why in problems]
                    return response
            elif srv.srv_type is SetParametersAtomically:
                problem = next((why for why in map(_problem, request.parameters) if why), None)
                if problem is not None:
                    response.result = refused(problem)
                    return response
            elif srv.srv_type is GetTypeDescription and not _HASH.fullmatch(request.type_hash):
                # checked here: rcl would log the client's string, unbounded
                response.successful = False
                response.failure_reason = (f"type_hash {quote(request.type_hash)} is not 'RIHS01_' followed by 64 "
                                           "lowercase hexadecimal digits")
                return response
            return original(request, response)
        except Exception as e:  # rclpy raising on a request: the client gets a refusal, the thread goes on
            kind = type(e).__name__
            log.error("%s: request failed inside rclpy (%s: %s); refused, still serving", name, kind,
                      clip(str(e), 200), extra=log_key(name, kind))
            fresh = srv.srv_type.Response()
            reason = f"internal error: {kind}: {clip(str(e), 200)}"
            if srv.srv_type is SetParameters:
                fresh.results = [refused(reason) for _ in request.parameters]
            elif srv.srv_type is SetParametersAtomically:
                fresh.result = refused(reason)
            elif hasattr(fresh, "successful"):  # get_type_description
                fresh.successful, fresh.failure_reason = False, reason
            return fresh

    return call


class NodeServices:
    """The main node's own services, answered by the receiver on the simulation thread.

    Args:
        node: The main node (created with :func:`sim_time_overrides`).
        receiver: Takes the requests.
        now_ns: The simulation's time [ns] (for the node's clock).
    """

    def __init__(self, node: Any, receiver: Any, now_ns: Callable[[], int]) -> None:
        from rclpy.time import Time

        self._clock = node.get_clock()
        self._now_ns = now_ns
        self._time = Time
        make_sim_time_read_only(node, "it is the source of simulated time and stamps everything with it")
        self.names: dict[str, str] = {}
        for srv in builtin_services(node):
            name = full_name(node, srv)
            receiver.add_service(srv, self.serve(srv, guard(srv, name, self._set_clock)))
            self.names[name] = _type_name(srv.srv_type)

    def _set_clock(self) -> None:
        self._clock.set_ros_time_override(self._time(nanoseconds=self._now_ns()))

    @staticmethod
    def serve(srv: Any, callback: Callable[[Any, Any], Any]) -> Callable[[Any, Any], None]:
        """The receiver's ``(request, header)`` callback of ``srv``."""
        def handle(request: Any, header: Any) -> None:
            srv.send_response(callback(request, srv.srv_type.Response()), header)

        return handle


def guard_node(node: Any) -> None:
    """Guard the own services of a node spun by an executor (the action node) in place; its ``use_sim_time`` stays
    false (its goal bookkeeping, acceptance stamps and result expiry, runs on wall time)."""
    make_sim_time_read_only(node, "its goal bookkeeping (acceptance stamps, result expiry) runs on wall time")
    for srv in builtin_services(node):
        srv.callback = guard(srv, full_name(node, srv))


def _type_name(srv_type: Any) -> str:
    module = srv_type.__module__.split(".")
    return f"{module[0]}/srv/{srv_type.__name__}"
