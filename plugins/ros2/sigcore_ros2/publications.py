"""Every publication declared through the core's contract (:mod:`sigcore.publish`) as a ROS 2 topic.

The transport names no feature: whatever the core and the world's features declare (the agents' ``publish``
entries of the API table, ``/tf_static``, a feature's ``/map`` or ``/referee/score``) becomes a publisher with the
QoS of its class, and every pushed field dictionary is filled into a message of the declared type.
"""

from __future__ import annotations

import array
import logging
import time
from collections.abc import Callable, Collection
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.publish import Publication, PublicationSink

from .cli.messages import message_class

if TYPE_CHECKING:
    from rclpy.node import Node

    from .qos import Qos

log = logging.getLogger("sigcore.ros2")

_ARRAY_CODES = {"float": "f", "double": "d", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
                "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q"}
"""``array.array`` type codes of numeric sequence fields (what rclpy accepts without a per-element check)."""


def fill_message(msg: Any, fields: dict[str, Any]) -> Any:
    """Set ``msg``'s fields from a field dictionary (nested dictionaries for nested messages, sequences as lists
    or numpy arrays, ``builtin_interfaces/Time`` as int [ns] or float [s]); returns ``msg``.

    Raises:
        KeyError: a field the message does not have (names the valid ones).
    """
    slots = msg.get_fields_and_field_types()
    for name, value in fields.items():
        kind = slots.get(name)
        if kind is None:
            raise KeyError(f"{type(msg).__name__} has no field {name!r}; fields: {', '.join(slots)}")
        if kind == "builtin_interfaces/Time":
            ns = int(value) if isinstance(value, int | np.integer) else round(float(value) * 1e9)
            t = getattr(msg, name)
            t.sec, t.nanosec = divmod(ns, 1_000_000_000)
        elif isinstance(value, dict):
            fill_message(getattr(msg, name), value)
        elif kind.startswith("sequence<") and "/" in kind:
            cls = message_class(kind[len("sequence<"):].rstrip(">").split(",")[0])
            setattr(msg, name, [fill_message(cls(), item) for item in value])
        elif kind.startswith("sequence<"):
            base = kind[len("sequence<"):].rstrip(">").split(",")[0]
            code = _ARRAY_CODES.get(base)
            if code is not None:
                seq = array.array(code)
                seq.frombytes(np.ascontiguousarray(value, dtype=np.dtype(code)).tobytes())
                setattr(msg, name, seq)
            else:
                setattr(msg, name, [str(v) for v in value] if base.startswith("string") else list(value))
        elif kind in ("double", "float"):
            setattr(msg, name, float(value))
        elif kind in _ARRAY_CODES:
            setattr(msg, name, int(value))
        elif kind == "boolean":
            setattr(msg, name, bool(value))
        else:
            setattr(msg, name, value)
    return msg


class PublicationEndpoints(PublicationSink):
    """A publisher per declared publication on ``node``.

    Args:
        node: The node that owns the publishers.
        qos: QoS profiles (per-topic overrides from the world apply).
        agent_topics: Whether the agents' ``<agent><suffix>`` publications (the sig_ros family) get endpoints
            (a collection: those of these agents only; a callable: those of the agents it says yes to, asked when
            the publication is declared, so that it can select agents spawned later).
    """

    def __init__(self, node: Node, qos: Qos,
                 agent_topics: bool | Collection[str] | Callable[[str], bool] = True,
                 before: Callable[[], None] | None = None) -> None:
        self.node = node
        self.before = before
        """Called before each value is published (the transport puts the step's time on /clock first)."""
        self.qos = qos
        self.agent_topics = agent_topics
        self.publishers: dict[str, tuple[Any, Any]] = {}
        self.names: dict[str, str] = {}
        """Topic -> ROS type of every endpoint created."""
        self.missing: set[str] = set()

    def _profile(self, publication: Publication) -> Any:
        q, topic = self.qos, publication.topic
        return {"state": q.state, "sensor": q.sensor, "events": q.events, "latched": q.latched,
                "tf": q.tf}[publication.qos](topic)

    def declare(self, publication: Publication) -> None:
        """Create the publisher (a type whose interface package is not built is left out with one warning)."""
        if publication.agent and not self._wanted(publication.agent):
            return
        if publication.topic in self.publishers:
            return
        try:
            cls = message_class(publication.full_type)
        except (ImportError, AttributeError):
            if publication.full_type not in self.missing:
                self.missing.add(publication.full_type)
                log.warning("no ROS 2 type %s (from %s): its topics are left out; rebuild the interfaces: "
                            "sigcore interfaces && python scripts/build_interfaces.py", publication.full_type,
                            publication.origin)
            return
        pub = self.node.create_publisher(cls, publication.topic, self._profile(publication))
        self.publishers[publication.topic] = (pub, cls)
        self.names[publication.topic] = publication.full_type

    def _wanted(self, agent: str) -> bool:
        """Whether the publications of ``agent`` get endpoints."""
        wanted = self.agent_topics
        if isinstance(wanted, bool):
            return wanted
        if callable(wanted):
            return wanted(agent)
        return agent in wanted

    def withdraw(self, publication: Publication) -> None:
        """Destroy the publisher of ``publication`` (its agent was deleted while running)."""
        entry = self.publishers.pop(publication.topic, None)
        self.names.pop(publication.topic, None)
        if entry is not None:
            self.node.destroy_publisher(entry[0])

    def wants(self, publication: Publication) -> bool:
        """Whether the topic's publisher has subscribers now."""
        entry = self.publishers.get(publication.topic)
        return entry is not None and entry[0].get_subscription_count() > 0

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        """Fill a message of the declared type and publish it."""
        entry = self.publishers.get(publication.topic)
        if entry is None:
            return
        pub, cls = entry
        if self.before is not None:
            self.before()
        pub.publish(fill_message(cls(), value))

    def flush(self, timeout: float) -> bool:
        """Wait until every subscriber acknowledged what was published (reliable topics), at most ``timeout`` [s]
        in all, so that what was published just before the end (a result) is not lost; whether all were."""
        from rclpy.duration import Duration

        end = time.monotonic() + timeout
        ok = True
        for pub, _ in self.publishers.values():
            left = max(0.0, end - time.monotonic())
            ok = pub.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9))) and ok
        return ok
