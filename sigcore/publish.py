"""The publication contract: what the core and features publish, declared once, turned into endpoints by transports.

A publisher (the core for the agents' ``publish`` entries of the API table, a feature for its own topics) declares
each :class:`Publication` (topic name, interface type, QoS class, latched or not) with
:meth:`Publications.declare` and pushes values through the returned :class:`Publisher`. A transport connects a
:class:`PublicationSink`: it is told of every declaration (those made before it connected too) and receives every
value, and turns them into endpoints without knowing which feature declared them. Nothing here imports a transport.

Values are plain field dictionaries shaped like the declared interface type (nested dictionaries for nested
messages, lists or numpy arrays for sequences); a field of type ``builtin_interfaces/Time`` takes an ``int`` of
nanoseconds (exact: :meth:`Stamp.of`) or a float of seconds.
"""

from __future__ import annotations

import logging
import math
import re
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, Literal

from pydantic import BaseModel

from .errors import PublicationError

log = logging.getLogger("sigcore")

QosClass = Literal["state", "sensor", "events", "latched", "tf"]
"""How a transport delivers a publication (REP-2003 classes):

- ``state``: the latest state (odometry, a score while it changes): reliable, volatile, a short queue;
- ``sensor``: raw sensor data (scans): reliable, volatile, keep last 5;
- ``events``: each message matters (collisions, scored events): reliable, a long queue;
- ``latched``: the last value is kept for late subscribers (a map, a final result): reliable, transient local;
- ``tf``: transforms (``tf2_msgs/msg/TFMessage``), merged into the transport's ``/tf``.
"""

DisplayKind = Literal["value", "log", "result"]
"""How a viewer shows a publication (``Publication.display``):

- ``value``: one line that always shows the latest value (a score);
- ``log``: one line per value, appended to a list (scored events);
- ``result``: a banner with the value, shown once it arrives (the task's result at the end).
"""

QOS_CLASSES: tuple[str, ...] = ("state", "sensor", "events", "latched", "tf")
_SHARED = ("tf",)
"""Classes of topics several declarers may share (``/tf``: each adds its own transforms)."""

_TOPIC = re.compile(r"^/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*$")
_TYPE = re.compile(r"^([a-z][a-z0-9_]*/msg/)?[A-Z][A-Za-z0-9]*$")


@dataclass(frozen=True)
class Publication:
    """One topic a publisher declares.

    Attributes:
        topic: The name: absolute (``/referee/score``) or an agent's endpoint (``robot_000_onCollisionMsg``).
        msg_type: The interface type: a full name (``std_msgs/msg/Int32``) or a ``sigcore_msgs`` message
            (``RefereeEvent``), whose definition is :attr:`model`.
        qos: The delivery class (:data:`QosClass`).
        doc: One line for people (``sigcore api`` prints it).
        origin: Who declared it: ``sigcore`` or a feature's name.
        agent: The agent it belongs to (per-agent endpoints of the API table), else empty.
        model: The pydantic model defining a ``sigcore_msgs`` type (generated into the interface package), or None
            for a standard type.
        display: How a viewer shows it (:data:`DisplayKind`); None: a viewer does not show it as text.
        display_format: The line a viewer shows, a :meth:`str.format` template over the value's fields (e.g.
            ``"score: {data}"``); empty: ``topic: field=value ...``.
    """

    topic: str
    msg_type: str
    qos: QosClass
    doc: str = ""
    origin: str = "sigcore"
    agent: str = ""
    model: type[BaseModel] | None = field(default=None, compare=False)
    display: DisplayKind | None = None
    display_format: str = ""

    def __post_init__(self) -> None:
        if not _TOPIC.match(self.topic):
            raise PublicationError(f"topic {self.topic!r} is not a valid name: letters, digits and '_', in "
                                   "'/'-separated tokens that start with a letter")
        if not _TYPE.match(self.msg_type):
            raise PublicationError(f"type {self.msg_type!r} of {self.topic!r} is not 'package/msg/Type' nor a "
                                   "sigcore_msgs type name (CamelCase)")
        if self.qos not in QOS_CLASSES:
            raise PublicationError(f"qos {self.qos!r} of {self.topic!r} is not one of {', '.join(QOS_CLASSES)}")
        if self.display not in (None, "value", "log", "result"):
            raise PublicationError(f"display {self.display!r} of {self.topic!r} is not one of value, log, result "
                                   "(or None)")

    def display_text(self, value: dict[str, Any]) -> str:
        """The line a viewer shows for ``value``: :attr:`display_format` filled with its fields, or
        ``topic: field=value ...``; a template that does not fit the value falls back to the latter."""
        if self.display_format:
            try:
                return self.display_format.format(**value)
            except (KeyError, IndexError, ValueError, TypeError, AttributeError):
                pass
        fields = " ".join(f"{k}={v}" for k, v in value.items() if not isinstance(v, (list, tuple, dict)))
        return f"{self.topic}: {fields}"

    @property
    def latched(self) -> bool:
        """Whether late subscribers get the last value."""
        return self.qos == "latched"

    @property
    def full_topic(self) -> str:
        """The topic's full name (an agent's endpoint is declared relative: ``robot_000_onRecvMsg``)."""
        return self.topic if self.topic.startswith("/") else "/" + self.topic

    @property
    def full_type(self) -> str:
        """The type's full name (``sigcore_msgs/msg/X`` for a bare ``X``)."""
        return self.msg_type if "/" in self.msg_type else f"sigcore_msgs/msg/{self.msg_type}"


@dataclass(frozen=True)
class Offered:
    """The QoS a publisher offers, as a recorder keeps it (rosbag2's ``offered_qos_profiles``): keep last
    ``depth``, reliable or best effort, transient local (latched) or volatile."""

    depth: int
    reliable: bool = True
    latched: bool = False


OFFERED: dict[str, Offered] = {"state": Offered(10), "sensor": Offered(5), "events": Offered(50),
                               "latched": Offered(1, latched=True), "tf": Offered(100)}
"""The QoS each class is offered with by default (REP-2003; the ROS 2 transport's defaults)."""


class PublicationSink(ABC):
    """What a transport (or a recorder) implements to receive publications."""

    takes_raw: bool = False
    """Whether the sink also takes the transports' own serialized messages (:meth:`raw`): a recorder does."""

    @abstractmethod
    def declare(self, publication: Publication) -> None:
        """Create the endpoint of ``publication`` (called for every declaration, past and future)."""

    @abstractmethod
    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        """Deliver one value stamped ``stamp_ns`` [ns of simulated time]. Called on the simulation thread."""

    def withdraw(self, publication: Publication) -> None:  # noqa: B027 - optional, does nothing by default
        """Remove the endpoint of ``publication`` (its agent was deleted while running); default: nothing."""

    def wants(self, publication: Publication) -> bool:
        """Whether values of ``publication`` reach anyone now (ROS 2: it has subscribers); default: True. Costly
        values (camera images) are computed only when some sink wants them."""
        return True

    def raw(self, topic: str, msg_type: str, offered: Offered, stamp_ns: int, data: bytes) -> None:  # noqa: B027
        """A message a transport published on a topic of its own (not declared here: ``/clock``, its ``/tf``, odometry,
        joint states, scans), already serialized (CDR) under its full name; only sinks that set :attr:`takes_raw`
        get them. Called on the simulation thread; default: nothing."""


class Publisher:
    """The handle a declarer pushes values through (returned by :meth:`Publications.declare`)."""

    def __init__(self, owner: Publications, publication: Publication) -> None:
        self._owner = owner
        self.publication = publication

    @property
    def active(self) -> bool:
        """Whether anything receives the values (build costly values only then; latched ones are kept anyway)."""
        return self._owner.has_sinks

    @property
    def wanted(self) -> bool:
        """Whether some sink wants the values now (:meth:`PublicationSink.wants`): render an image only then."""
        return self._owner.wanted(self.publication)

    def publish(self, value: dict[str, Any], stamp_ns: int | None = None) -> None:
        """Push ``value`` (a field dictionary of the declared type), stamped with ``stamp_ns`` [ns] (default: the
        current step's time)."""
        self._owner.push(self.publication, value, stamp_ns)


class Publications:
    """Every publication of one simulation: the one owner of declarations, latched values and connected sinks.

    Args:
        clock_ns: Returns the current simulated time [ns] (the default stamp).
        on_first_sink: Called once, when the first sink connects (the simulation attaches its event sources then,
            so a run without a transport computes nothing for them).
    """

    def __init__(self, clock_ns: Callable[[], int], on_first_sink: Callable[[], None] | None = None) -> None:
        self._clock_ns = clock_ns
        self._on_first_sink = on_first_sink
        self._declared: dict[str, Publication] = {}
        self._sinks: list[PublicationSink] = []
        self._latched: dict[str, tuple[int, dict[str, Any]]] = {}
        self._failed: set[tuple[int, str]] = set()
        self._raw: list[PublicationSink] = []

    # ------------------------------------------------------------------ declaring
    def declare(self, publication: Publication) -> Publisher:
        """Declare ``publication``; connected sinks create its endpoint now.

        Raises:
            PublicationError: the topic is already declared, unless both declarations are the same ``tf`` topic.
        """
        old = self._declared.get(publication.topic)
        if old is not None:
            if old.msg_type == publication.msg_type and old.qos == publication.qos and old.qos in _SHARED:
                return Publisher(self, old)
            raise PublicationError(f"topic {publication.topic!r} is already declared by {old.origin} "
                                   f"({old.msg_type}, {old.qos}); only {', '.join(_SHARED)} topics of one type are "
                                   "shared by several declarers")
        self._declared[publication.topic] = publication
        for sink in list(self._sinks):
            self._call(sink, "declare", sink.declare, publication)
        return Publisher(self, publication)

    def withdraw(self, topic: str) -> None:
        """Forget the publication ``topic`` (its agent was deleted while running): every sink removes its endpoint,
        its latched value is dropped, and pushing through its publisher is an error. Unknown topics are ignored."""
        publication = self._declared.pop(topic, None)
        if publication is None:
            return
        self._latched.pop(topic, None)
        for sink in list(self._sinks):
            self._call(sink, "withdraw", sink.withdraw, publication)

    @property
    def declared(self) -> list[Publication]:
        """Every declared publication, in declaration order."""
        return list(self._declared.values())

    def get(self, topic: str) -> Publication:
        """The publication named ``topic``; ``PublicationError`` listing the declared ones otherwise."""
        try:
            return self._declared[topic]
        except KeyError:
            raise PublicationError(f"no publication {topic!r}; declared: "
                                   f"{', '.join(self._declared) or 'none'}") from None

    # ------------------------------------------------------------------ sinks
    @property
    def has_sinks(self) -> bool:
        """Whether a sink is connected."""
        return bool(self._sinks)

    def connect(self, sink: PublicationSink) -> None:
        """Connect ``sink``: it is told of every declaration so far and then of every new one and every value; the
        last value of each latched publication is delivered to it at once."""
        if sink in self._sinks:
            return
        if self._on_first_sink is not None:
            first, self._on_first_sink = self._on_first_sink, None
            first()
        self._sinks.append(sink)
        self._raw = [s for s in self._sinks if s.takes_raw]
        for publication in self._declared.values():
            self._call(sink, "declare", sink.declare, publication)
        for topic, (stamp, value) in self._latched.items():
            self._call(sink, "publish", sink.publish, self._declared[topic], stamp, value)

    def wanted(self, publication: Publication) -> bool:
        """Whether any connected sink wants values of ``publication`` now (a sink that fails to say counts as
        wanting them)."""
        for sink in self._sinks:
            try:
                if sink.wants(publication):
                    return True
            except Exception:
                return True
        return False

    def disconnect(self, sink: PublicationSink) -> None:
        """Stop delivering to ``sink`` (no error if it was not connected)."""
        if sink in self._sinks:
            self._sinks.remove(sink)
        self._raw = [s for s in self._sinks if s.takes_raw]

    @property
    def raw_wanted(self) -> bool:
        """Whether a connected sink takes the transports' own serialized messages (a transport serializes a message
        it would not otherwise only when this is true)."""
        return bool(self._raw)

    def raw(self, topic: str, msg_type: str, offered: Offered, stamp_ns: int, data: bytes) -> None:
        """Hand a transport's own serialized message to the sinks that take them (:meth:`PublicationSink.raw`); a
        sink's failure is logged once per topic, like :meth:`push`."""
        for sink in self._raw:
            try:
                sink.raw(topic, msg_type, offered, stamp_ns, data)
            except Exception:
                key = (id(sink), f"raw:{topic}")
                if key not in self._failed:
                    self._failed.add(key)
                    log.exception("raw %s by %s failed (logged once; the simulation goes on)", topic,
                                  type(sink).__name__)

    # ------------------------------------------------------------------ values
    def push(self, publication: Publication, value: dict[str, Any], stamp_ns: int | None = None) -> None:
        """Deliver ``value`` to every sink (see :meth:`Publisher.publish`)."""
        if self._declared.get(publication.topic) is not publication:
            raise PublicationError(f"publication {publication.topic!r} is not declared here")
        stamp = self._clock_ns() if stamp_ns is None else int(stamp_ns)
        if publication.qos == "latched":
            self._latched[publication.topic] = (stamp, value)
        for sink in self._sinks:
            self._call(sink, "publish", sink.publish, publication, stamp, value)

    def latest(self, topic: str) -> tuple[int, dict[str, Any]] | None:
        """``(stamp [ns], value)`` last pushed on a latched publication, or None."""
        return self._latched.get(topic)

    def _call(self, sink: PublicationSink, what: str, method: Any, *args: Any) -> None:
        """A sink's failure is logged once per (sink, publication) and never reaches the simulation."""
        try:
            method(*args)
        except Exception:
            key = (id(sink), f"{what}:{args[0].topic}")
            if key not in self._failed:
                self._failed.add(key)
                log.exception("%s of %s by %s failed (logged once; the simulation goes on)", what,
                              args[0].topic, type(sink).__name__)


@dataclass(frozen=True)
class Stamp:
    """Helpers for exact stamps in integer nanoseconds."""

    @staticmethod
    def of(step_count: int, dt: float) -> int:
        """The time of step ``step_count`` at timestep ``dt`` [s], in [ns] (exact for timesteps in whole ns)."""
        return step_count * round(dt * 1e9)


def transform_fields(parent: str, child: str, stamp_ns: int, xyz: Iterable[float],
                     wxyz: Iterable[float]) -> dict[str, Any]:
    """The fields of a ``geometry_msgs/TransformStamped`` ``parent -> child``: translation [m], rotation
    (w, x, y, z)."""
    x, y, z = (float(v) for v in xyz)
    w, qx, qy, qz = (float(v) for v in wxyz)
    return {"header": {"stamp": stamp_ns, "frame_id": parent}, "child_frame_id": child,
            "transform": {"translation": {"x": x, "y": y, "z": z},
                          "rotation": {"x": qx, "y": qy, "z": qz, "w": w}}}


def planar_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """``(w, x, y, z)`` of a rotation by ``yaw`` [rad] about z."""
    return math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)
