"""The ROS 2 graph as the ``sigcore ros`` commands see it: one hidden, short-lived rclpy node (:class:`Graph`) that
lists topics and services without its own endpoints, waits for a name to appear (DDS discovery is asynchronous),
checks names, says which names exist when one does not, and picks a subscription QoS matching the publishers'."""

from __future__ import annotations

import difflib
import enum
import os
import signal
import time
from collections.abc import Callable
from typing import Any

import typer

from sigcore.text import quote

from ..exceptions import RosToolError

DISCOVERY_WAIT = 5.0
"""Default ``--wait`` of echo, hz, call and record: how long a topic or service may take to appear [s] (they go on
as soon as it does). Fast DDS discovers a new participant's peers within 0.1 s most times, but often only after 2 to
3 s (measured on a loaded 2-core machine, multicast and localhost discovery alike)."""
LIST_LIMIT = 40
"""An error naming an unknown topic or service lists at most this many of those that exist [names]."""

NO_RCLPY = ("rclpy cannot be imported ({}): install ROS 2 Jazzy's Python wheels (scripts/setup.sh) or source a ROS 2 "
            "installation")


class Reliability(enum.StrEnum):
    """``--qos``: the subscription's reliability (default: chosen from the publishers')."""

    reliable = "reliable"
    best_effort = "best_effort"


def domain() -> str:
    """``ROS_DOMAIN_ID=N`` of this environment, for error lines."""
    return f"ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID') or '0'}"


def is_hidden(name: str) -> bool:
    """Whether a topic or service name is hidden (a token starting with ``_``), as ``ros2 topic list`` hides it."""
    return any(token.startswith("_") for token in name.split("/"))


def listing(wanted: str, found: dict[str, list[str]], what: str) -> str:
    """``; did you mean X? topics: a, b, c`` for an error line: the names like ``wanted`` first, then every name that
    is not hidden, sorted (at most :data:`LIST_LIMIT`, then how many more)."""
    names = sorted(n for n in found if not is_hidden(n))
    close = difflib.get_close_matches(wanted, names, n=3, cutoff=0.6)
    text = f"; did you mean {' or '.join(close)}?" if close else ";"
    shown = names[:LIST_LIMIT]
    more = ""
    if len(names) > LIST_LIMIT:
        more = f", ... and {len(names) - LIST_LIMIT} more" + (" (sigcore ros topics lists them)" if what == "topics"
                                                              else "")
    return f"{text} {what}: {', '.join(shown) or 'none'}{more}"


def full_name(name: str, service: bool = False) -> str:
    """``name`` made absolute (``chatter`` -> ``/chatter``) and checked against ROS 2's naming rules.

    Raises:
        RosToolError: rclpy cannot be imported, or the name is not valid.
    """
    try:
        from rclpy.exceptions import InvalidServiceNameException, InvalidTopicNameException
        from rclpy.validate_full_topic_name import validate_full_topic_name
    except ImportError as e:
        raise RosToolError(NO_RCLPY.format(e)) from None

    full = name if name.startswith("/") else "/" + name
    try:
        validate_full_topic_name(full, is_service=service)
    except (InvalidTopicNameException, InvalidServiceNameException) as e:
        reason = str(e).splitlines()[0].rstrip(":")
        raise RosToolError(f"{quote(name)} is not a valid {'service' if service else 'topic'} name ({reason})") \
            from None
    return full


class Graph:
    """One hidden rclpy node in a context of its own, with an executor; its own endpoints are left out of every
    answer. In a ``with`` block, SIGINT and SIGTERM set ``stop.now`` (rclpy's own handlers are off).

    Raises:
        RosToolError: rclpy cannot be imported or ROS 2 cannot start.
    """

    def __init__(self, command: str) -> None:
        try:
            import rclpy
            from rclpy.executors import SingleThreadedExecutor
            from rclpy.signals import SignalHandlerOptions
        except ImportError as e:
            raise RosToolError(NO_RCLPY.format(e)) from None
        self.rclpy = rclpy
        self.context = rclpy.Context()
        try:
            rclpy.init(args=[], context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        except Exception as e:  # rclpy's RCLError and friends: no middleware, a bad ROS_DOMAIN_ID
            raise RosToolError(f"ROS 2 cannot start ({type(e).__name__}: {str(e).splitlines()[0]})", 1) from None
        self.name = f"_sigcore_ros_{command}_{os.getpid()}"
        self.node = rclpy.create_node(self.name, context=self.context, enable_rosout=False,
                                      start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.stop = Stop()

    def __enter__(self) -> Graph:
        self.stop.__enter__()
        return self

    def __exit__(self, *_: object) -> None:
        self.stop.__exit__()
        self.close()

    def close(self) -> None:
        try:
            self.executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
        finally:
            self.rclpy.try_shutdown(context=self.context)

    def spin(self, seconds: float) -> None:
        """Process callbacks for ``seconds`` [s] (at least once)."""
        end = time.monotonic() + seconds
        while True:
            self.executor.spin_once(timeout_sec=max(0.0, min(0.05, end - time.monotonic())))
            if time.monotonic() >= end:
                return

    def _own(self, info: Any) -> bool:
        return bool(info.node_name == self.name and info.node_namespace == "/")

    def publishers(self, topic: str) -> list[Any]:
        """The publishers of ``topic`` (``TopicEndpointInfo``: node, QoS, type hash), ours left out."""
        return [i for i in self.node.get_publishers_info_by_topic(topic) if not self._own(i)]

    def subscribers(self, topic: str) -> list[Any]:
        """The subscriptions of ``topic``, ours left out."""
        return [i for i in self.node.get_subscriptions_info_by_topic(topic) if not self._own(i)]

    def topics(self, hidden: bool = False) -> dict[str, list[str]]:
        """Every topic with its types, leaving out those only this node has (its ``/parameter_events``) and, unless
        ``hidden``, hidden ones."""
        found = {}
        for name, types in self.node.get_topic_names_and_types():
            if (hidden or not is_hidden(name)) and (self.publishers(name) or self.subscribers(name)):
                found[name] = list(types)
        return found

    def services(self) -> dict[str, list[str]]:
        """Every service with its types."""
        return {name: list(types) for name, types in self.node.get_service_names_and_types()}

    def wait_for(self, lookup: Callable[[], dict[str, list[str]]], name: str, wait: float
                 ) -> tuple[list[str] | None, dict[str, list[str]]]:
        """Poll ``lookup()`` up to ``wait`` [s] until it has ``name``: ``(its types or None, the last answer)``."""
        end = time.monotonic() + wait
        while True:
            found = lookup()
            if name in found:
                return found[name], found
            if time.monotonic() >= end:
                return None, found
            if self.stop.now:
                raise typer.Exit(130)
            self.spin(0.05)

    def topic_type(self, topic: str, wait: float) -> str:
        """The one type of ``topic``, once the graph shows it (up to ``wait`` [s]).

        Raises:
            RosToolError: it does not appear (listing the topics that exist) or has several types.
        """
        types, found = self.wait_for(lambda: self.topics(hidden=True), topic, wait)
        if types is None:
            raise RosToolError(f"topic {topic} is not on the ROS 2 graph ({domain()}, after {wait:g} s)"
                               f"{listing(topic, found, 'topics')}")
        if len(types) != 1:
            raise RosToolError(f"topic {topic} has several types ({', '.join(types)}); cannot choose one")
        return types[0]


class Stop:
    """SIGINT and SIGTERM set ``now`` (rclpy's own handlers are off) while in a ``with`` block."""

    def __init__(self) -> None:
        self.now = False
        self.signal: int | None = None

    def __enter__(self) -> Stop:
        def handler(signum: int, _frame: Any) -> None:
            self.now = True
            self.signal = signum

        self._previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
        return self

    def __exit__(self, *_: object) -> None:
        for s, h in self._previous.items():
            signal.signal(s, h)


def matching_qos(publishers: list[Any], depth: int, reliability: Reliability | None = None) -> Any:
    """A subscription's QoS that matches every publisher: reliable only if all offer it (or ``reliability``),
    transient local (latched messages arrive) only if all offer it."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    reliable = all(p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in publishers)
    if reliability is not None:
        reliable = reliability == Reliability.reliable
    latched = bool(publishers) and all(p.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
                                       for p in publishers)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)
