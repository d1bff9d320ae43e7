"""``sigcore ros``: ROS 2 introspection for users who installed sigcore with pip and have no ``ros2`` command.

Thin wrappers over rclpy, each in one short-lived hidden node (``_sigcore_ros_<command>_<pid>``, no ``/rosout``, no
parameter services; its own endpoints are left out of every list and count):

- ``sigcore ros topics``: the topics on the graph, with their types and publisher / subscriber counts;
- ``sigcore ros echo TOPIC``: messages as YAML, ``---`` between them;
- ``sigcore ros hz TOPIC``: the rate of a topic (raw subscription: nothing is deserialized);
- ``sigcore ros call SERVICE YAML``: one service call, the response as YAML;
- ``sigcore ros record DIR``: a rosbag2 directory (MCAP) of topics received over DDS, written by
  :class:`sigcore.record.bag.BagWriter` with the bytes as they came.

DDS discovery is asynchronous: every command first waits (``--wait``) for the graph to show what it needs. Bad input
(an unknown topic or service, a type that cannot be imported, malformed YAML, an unknown field) ends the command with
one line on stderr and exit status 2; a timeout or a topic that stays silent with exit status 1. Where ROS 2 is
installed, the real ``ros2 topic list / echo / hz``, ``ros2 service call`` and ``ros2 bag record`` do the same.
See ``docs/ros-tools.md``.
"""

from __future__ import annotations

import difflib
import enum
import importlib
import math
import os
import re
import signal
import statistics
import sys
import time
from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer
import yaml
from rich.console import Console

from sigcore.text import quote

from .exceptions import RosToolError

ros_app = typer.Typer(help="ROS 2 introspection without a ROS install: topics, echo, hz, call, record. Where ROS 2 is "
                      "installed, the real ros2 CLI does the same.", no_args_is_help=True,
                      rich_markup_mode=None)

err = Console(stderr=True, highlight=False, markup=False, soft_wrap=True)

TRUNCATE_LENGTH = 128
"""Default of ``echo --truncate-length``: longer arrays, sequences, strings and byte strings are cut there (``...``
marks the cut), like ``ros2 topic echo``'s default."""
DISCOVERY_WAIT = 5.0
"""Default ``--wait`` of echo, hz, call and record: how long a topic or service may take to appear [s] (they go on
as soon as it does). Fast DDS discovers a new participant's peers within 0.1 s most times, but often only after 2 to
3 s (measured on a loaded 2-core machine, multicast and localhost discovery alike)."""
TOPICS_WAIT = 3.0
"""Default ``--wait`` of ``topics``: how long the graph is watched before it is listed [s] (see
:data:`DISCOVERY_WAIT`)."""
SETTLE = 0.5
"""``topics`` goes on waiting past ``--wait`` while the graph changed in the last ``SETTLE`` seconds [s]."""
RESCAN_PERIOD = 1.0
"""``record`` re-reads the graph this often for new topics [s] (every 0.1 s during its first ``--wait``)."""
RECORD_DEPTH = 100
"""Depth of the recorder's subscriptions (messages waiting to be written) [messages]."""
UNKNOWN_DEPTH = 10
"""The depth written as a topic's offered QoS when the graph does not tell the publishers' (remote DDS endpoints
never tell their history depth)."""
LIST_LIMIT = 40
"""An error naming an unknown topic or service lists at most this many of those that exist [names]."""
PENDING_LIMIT = 10_000
"""``record --use-sim-time``: at most this many messages received before the first /clock are kept [messages]."""


class Reliability(enum.StrEnum):
    """``--qos``: the subscription's reliability (default: chosen from the publishers')."""

    reliable = "reliable"
    best_effort = "best_effort"


@contextmanager
def _command(name: str) -> Iterator[None]:
    """Turn a :class:`RosToolError` into one line on stderr and its exit status; a closed stdout ends quietly."""
    try:
        yield
    except RosToolError as e:
        err.print(f"sigcore ros {name}: {e}")
        raise typer.Exit(e.code) from None
    except KeyboardInterrupt:  # Ctrl-C before the command's own handler was installed (while rclpy starts)
        raise typer.Exit(130) from None
    except BrokenPipeError:  # `sigcore ros echo ... | head`: the reader went away
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        raise typer.Exit(0) from None


_NO_RCLPY = ("rclpy cannot be imported ({}): install ROS 2 Jazzy's Python wheels (scripts/setup.sh) or source a ROS 2 "
             "installation")


def _domain() -> str:
    return f"ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID') or '0'}"


def _hidden(name: str) -> bool:
    """Whether a topic or service name is hidden (a token starting with ``_``), as ``ros2 topic list`` hides it."""
    return any(token.startswith("_") for token in name.split("/"))


def _listing(wanted: str, found: dict[str, list[str]], what: str) -> str:
    """``; did you mean X? topics: a, b, c`` for an error line: the names like ``wanted`` first, then every name that
    is not hidden, sorted (at most :data:`LIST_LIMIT`, then how many more)."""
    names = sorted(n for n in found if not _hidden(n))
    close = difflib.get_close_matches(wanted, names, n=3, cutoff=0.6)
    text = f"; did you mean {' or '.join(close)}?" if close else ";"
    shown = names[:LIST_LIMIT]
    more = ""
    if len(names) > LIST_LIMIT:
        more = f", ... and {len(names) - LIST_LIMIT} more" + (" (sigcore ros topics lists them)" if what == "topics"
                                                              else "")
    return f"{text} {what}: {', '.join(shown) or 'none'}{more}"


def _full_name(name: str, service: bool = False) -> str:
    """``name`` made absolute (``chatter`` -> ``/chatter``) and checked against ROS 2's naming rules."""
    try:
        from rclpy.exceptions import InvalidServiceNameException, InvalidTopicNameException
        from rclpy.validate_full_topic_name import validate_full_topic_name
    except ImportError as e:
        raise RosToolError(_NO_RCLPY.format(e)) from None

    full = name if name.startswith("/") else "/" + name
    try:
        validate_full_topic_name(full, is_service=service)
    except (InvalidTopicNameException, InvalidServiceNameException) as e:
        reason = str(e).splitlines()[0].rstrip(":")
        raise RosToolError(f"{quote(name)} is not a valid {'service' if service else 'topic'} name ({reason})") \
            from None
    return full


# ---------------------------------------------------------------------- the graph
class _Graph:
    """One hidden rclpy node in a context of its own, with an executor; its own endpoints are left out of every
    answer. In a ``with`` block, SIGINT and SIGTERM set ``stop.now`` (rclpy's own handlers are off)."""

    def __init__(self, command: str) -> None:
        try:
            import rclpy
            from rclpy.executors import SingleThreadedExecutor
            from rclpy.signals import SignalHandlerOptions
        except ImportError as e:
            raise RosToolError(_NO_RCLPY.format(e)) from None
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
        self.stop = _Stop()

    def __enter__(self) -> _Graph:
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
            if (hidden or not _hidden(name)) and (self.publishers(name) or self.subscribers(name)):
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
            raise RosToolError(f"topic {topic} is not on the ROS 2 graph ({_domain()}, after {wait:g} s)"
                               f"{_listing(topic, found, 'topics')}")
        if len(types) != 1:
            raise RosToolError(f"topic {topic} has several types ({', '.join(types)}); cannot choose one")
        return types[0]


class _Stop:
    """SIGINT and SIGTERM set ``now`` (rclpy's own handlers are off) while in a ``with`` block."""

    def __init__(self) -> None:
        self.now = False
        self.signal: int | None = None

    def __enter__(self) -> _Stop:
        def handler(signum: int, _frame: Any) -> None:
            self.now = True
            self.signal = signum

        self._previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
        return self

    def __exit__(self, *_: object) -> None:
        for s, h in self._previous.items():
            signal.signal(s, h)


def _qos(publishers: list[Any], depth: int, reliability: Reliability | None = None) -> Any:
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


# ---------------------------------------------------------------------- types
def interface_class(typename: str, kind: str = "msg") -> Any:
    """The rclpy class of ``pkg/msg/Name`` (``kind`` ``msg``) or ``pkg/srv/Name`` (``srv``): through
    ``rosidl_runtime_py.utilities`` when it is installed, else by importing ``pkg.msg``.

    Raises:
        RosToolError: not a type name, or its package is not installed (naming what to install).
    """
    parts = typename.split("/")
    if len(parts) != 3 or parts[1] != kind or not all(parts):
        raise RosToolError(f"{quote(typename)} is not a ROS 2 {kind} type name (package/{kind}/Name)")
    package, _, name = parts
    try:
        from rosidl_runtime_py import utilities
    except ImportError:
        utilities = None
    try:
        if utilities is not None:
            return utilities.get_message(typename) if kind == "msg" else utilities.get_service(typename)
        module = importlib.import_module(f"{package}.{kind}")
    except (ImportError, AttributeError, ValueError):
        module = None
    if module is not None:
        cls = getattr(module, name, None)
        if cls is not None:
            return cls
        raise RosToolError(f"type {typename} cannot be imported: the installed package {package!r} has no {kind} "
                           f"{name!r} (not the version the publisher uses?)")
    raise RosToolError(
            f"type {typename} cannot be imported: its Python package {package!r} (generated interfaces) is not in "
            f"this environment ({sys.prefix}); install it (pip install ros-jazzy-{package.replace('_', '-')} where "
            "that wheel exists; sigcore's own interface packages: scripts/setup.sh) or source a ROS 2 workspace "
            "that has it")


def _fields(msg: Any) -> dict[str, str]:
    fields: dict[str, str] = msg.get_fields_and_field_types()
    return fields


def _is_message(value: Any) -> bool:
    return hasattr(value, "get_fields_and_field_types")


@dataclass
class YamlStyle:
    """How :func:`to_plain` abbreviates: ``truncate`` (0: never), ``no_arr`` and ``no_str`` like ``ros2 topic echo``'s
    ``--truncate-length``, ``--no-arr`` and ``--no-str``."""

    truncate: int = TRUNCATE_LENGTH
    no_arr: bool = False
    no_str: bool = False


def to_plain(value: Any, style: YamlStyle | None = None) -> Any:
    """A ROS message (or field value) as plain Python data for YAML: fields in message order, nested messages as
    mappings, arrays as lists, longer ones cut at ``style.truncate`` with a last item ``'...'``."""
    style = style or YamlStyle()
    if _is_message(value):
        out: dict[str, Any] = {}
        for name, ftype in _fields(value).items():
            v = getattr(value, name)
            if style.no_arr and ("[" in ftype or ftype.startswith("sequence<")):
                out[name] = f"<{ftype}, length: {len(v)}>"
            elif style.no_str and ftype.startswith(("string", "wstring")):
                out[name] = f"<{ftype}, length: {len(v)}>"
            else:
                out[name] = to_plain(v, style)
        return out
    if isinstance(value, str):
        return value[:style.truncate] + "..." if style.truncate and len(value) > style.truncate else value
    if isinstance(value, bytes | bytearray):
        if len(value) == 1:  # a `byte` field
            return value[0]
        value = list(value)
    if hasattr(value, "tolist") and not isinstance(value, list):  # numpy arrays and scalars, array.array
        value = value.tolist()
    if isinstance(value, list | tuple):
        items = list(value)
        cut = bool(style.truncate) and len(items) > style.truncate
        plain = [to_plain(v, style) for v in (items[:style.truncate] if cut else items)]
        return [*plain, "..."] if cut else plain
    return value


def to_yaml(value: Any, style: YamlStyle | None = None) -> str:
    """``value`` (a message or a field's value) as YAML text like ``ros2 topic echo`` prints it, ending in a
    newline."""
    plain = to_plain(value, style)
    text = yaml.safe_dump(plain, sort_keys=False, default_flow_style=False, allow_unicode=True, width=1_000_000)
    if not isinstance(plain, dict | list) and text.endswith("\n...\n"):
        text = text[:-4]
    return text


def field_of(msg: Any, path: list[str], typename: str) -> Any:
    """``msg.a.b`` for ``path`` ``['a', 'b']``.

    Raises:
        RosToolError: a name that is not a field (naming the fields there are).
    """
    value = msg
    for i, name in enumerate(path):
        where = ".".join(path[:i]) or typename
        if not _is_message(value):
            raise RosToolError(f"--field {'.'.join(path)}: {where} is not a message, it has no field {name!r}")
        fields = _fields(value)
        if name not in fields:
            raise RosToolError(f"--field {'.'.join(path)}: {where} has no field {name!r}; its fields: "
                               f"{', '.join(fields) or 'none'}")
        value = getattr(value, name)
    return value


def _slot(msg: Any, name: str) -> Any:
    """The rosidl_parser type of field ``name`` of ``msg``."""
    return dict(zip(_fields(msg), type(msg).SLOT_TYPES, strict=True))[name]


def _namespaced_class(t: Any) -> Any:
    return getattr(importlib.import_module(".".join(t.namespaces)), t.name)


def checked(cls: Any) -> Any:
    """A new message of ``cls`` whose field setters check types, ranges and lengths (rclpy skips those checks unless
    ``ROS_PYTHON_CHECK_FIELDS=1``, and serializes a wrong value into garbage)."""
    try:
        return cls(check_fields=True)
    except TypeError:  # a class generated before Jazzy: it always checks
        return cls()


def fill(msg: Any, values: Any, where: str) -> Any:
    """Set the fields of ``msg`` (a request, made by :func:`checked`) from ``values``, a mapping read from YAML:
    nested messages as mappings, sequences of messages as lists of mappings, integers where floats are expected.
    Returns ``msg``.

    Raises:
        RosToolError: an unknown field (naming the valid ones), a mapping where a value is expected or a value
            that does not fit its field (naming the field and its type).
    """
    from rosidl_parser.definition import AbstractNestedType, NamespacedType

    if not isinstance(values, dict):
        raise RosToolError(f"{where} is a message ({type(msg).__name__}): give a mapping of its fields, not "
                           f"{quote(values)}")
    fields = _fields(msg)
    for key, value in values.items():
        here = f"{where}.{key}"
        if key not in fields:
            raise RosToolError(f"{where} has no field {quote(key)}; its fields: {', '.join(fields) or 'none'}")
        ftype, slot = fields[key], _slot(msg, key)
        if isinstance(slot, NamespacedType):
            value = fill(checked(_namespaced_class(slot)), value, here)
        elif isinstance(slot, AbstractNestedType) and isinstance(slot.value_type, NamespacedType):
            if not isinstance(value, list):
                raise RosToolError(f"{here} is {ftype}: give a list of mappings, not {quote(value)}")
            cls = _namespaced_class(slot.value_type)
            value = [fill(checked(cls), item, f"{here}[{i}]") for i, item in enumerate(value)]
        else:
            value = _coerce(ftype, value, here)
        try:
            setattr(msg, key, value)
        except (AssertionError, TypeError, ValueError, OverflowError) as e:
            detail = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise RosToolError(f"{here} is {ftype}: {quote(value)} does not fit ({detail})") from None
    return msg


_FLOATS = ("float", "double", "long double")


def _coerce(ftype: str, value: Any, where: str) -> Any:
    """A YAML value made the Python type rclpy expects for a field of ``ftype`` where that is lossless."""
    sequence = re.fullmatch(r"sequence<(.+?)(?:, \d+)?>", ftype) or re.fullmatch(r"(.+)\[\d+\]", ftype)
    base, nested = (sequence.group(1), True) if sequence else (ftype, False)

    def one(v: Any) -> Any:
        if isinstance(v, dict | list):
            raise RosToolError(f"{where} is {ftype}: {quote(v)} is not a {base}")
        if base in _FLOATS and isinstance(v, int) and not isinstance(v, bool):
            return float(v)
        if base == "octet" and isinstance(v, int) and not isinstance(v, bool) and 0 <= v < 256:
            return bytes([v])
        return v

    if nested:
        if not isinstance(value, list):
            raise RosToolError(f"{where} is {ftype}: give a list, not {quote(value)}")
        return [one(v) for v in value]
    return one(value)


# ---------------------------------------------------------------------- topics
@ros_app.command("topics")
def topics_command(
    types: Annotated[bool, typer.Option("--types", "-t", help="show each topic's type(s)")] = False,
    counts: Annotated[bool, typer.Option("--counts", "-c", help="show publisher and subscriber counts")] = False,
    wait: Annotated[float, typer.Option("--wait", min=0, help="watch the graph this long before listing (DDS "
                                        "discovery is asynchronous), longer while it still changes (seconds)")]
        = TOPICS_WAIT,
    include_hidden: Annotated[bool, typer.Option("--include-hidden", help="also hidden topics (a name part "
                                                 "starting with _)")] = False,
) -> None:
    """Every topic on the ROS 2 graph, sorted; -t adds types, -c publisher and subscriber counts. Where ROS 2 is
    installed, `ros2 topic list -t -v` does the same."""
    with _command("topics"), _Graph("topics") as graph:
        found = _settled(graph, include_hidden, wait)
        if not found:
            err.print(f"sigcore ros topics: no topic on the ROS 2 graph ({_domain()}) after {2 * wait:g} s")
            return
        for name in sorted(found):
            line = name
            if types:
                line += f" [{', '.join(found[name])}]"
            if counts:
                p, s = len(graph.publishers(name)), len(graph.subscribers(name))
                line += f" ({p} publisher{'' if p == 1 else 's'}, {s} subscriber{'' if s == 1 else 's'})"
            print(line, flush=True)


def _settled(graph: _Graph, hidden: bool, wait: float) -> dict[str, list[str]]:
    """The topics after ``wait`` [s], or later while the graph is still empty or changing (a node with hundreds of
    endpoints arrives over a few tenths of a second): until it has not changed for :data:`SETTLE` s, at most
    ``2 * wait``."""
    start = time.monotonic()
    found: dict[str, list[str]] = {}
    changed = start
    while True:
        now = graph.topics(hidden)
        t = time.monotonic()
        if now != found:
            found, changed = now, t
        if (t - start >= wait and found and t - changed >= SETTLE) or t - start >= 2 * wait or graph.stop.now:
            return found
        graph.spin(0.1)


# ---------------------------------------------------------------------- echo
@ros_app.command("echo")
def echo_command(
    topic: Annotated[str, typer.Argument(help="the topic, e.g. /robot_000/odom")],
    once: Annotated[bool, typer.Option("--once", help="print the first message and exit")] = False,
    count: Annotated[int, typer.Option("--count", "-n", min=0, help="exit after this many messages; 0: "
                                       "never")] = 0,
    timeout: Annotated[float, typer.Option("--timeout", min=0, help="stop after this long (seconds); exit 1 if fewer "
                                           "messages than asked (or none) arrived; 0: no limit")] = 0.0,
    qos: Annotated[Reliability | None, typer.Option("--qos", help="subscribe reliable or best_effort (default: "
                                                    "reliable only if every publisher is)")] = None,
    truncate_length: Annotated[int, typer.Option("--truncate-length", "-l", min=0, help="cut arrays and strings "
                                                 "longer than this (a last item '...'); 0: never")]
        = TRUNCATE_LENGTH,
    no_arr: Annotated[bool, typer.Option("--no-arr", help="print array fields as their type and length")] = False,
    no_str: Annotated[bool, typer.Option("--no-str", help="print string fields as their type and length")] = False,
    field: Annotated[str | None, typer.Option("--field", "-f", help="print only this field (dotted: "
                                              "header.stamp)")] = None,
    wait: Annotated[float, typer.Option("--wait", min=0, help="how long the topic may take to appear on the "
                                        "graph (seconds)")] = DISCOVERY_WAIT,
) -> None:
    """Print a topic's messages as YAML, --- after each, like `ros2 topic echo` (which does the same where ROS 2 is
    installed). The type comes from the graph; the QoS matches the publishers' (latched topics such as /tf_static
    give their last messages)."""
    with _command("echo"):
        topic = _full_name(topic)
        want = 1 if once else count
        path = field.split(".") if field else []
        style = YamlStyle(truncate_length, no_arr, no_str)
        with _Graph("echo") as graph:
            stop = graph.stop
            typename = graph.topic_type(topic, wait)
            cls = interface_class(typename)
            if path:
                field_of(cls(), path, typename)
            received = 0

            def show(msg: Any) -> None:
                nonlocal received
                if want and received >= want:
                    return
                received += 1
                sys.stdout.write(to_yaml(field_of(msg, path, typename), style) + "---\n")
                sys.stdout.flush()

            received_all = _listen(graph, stop, topic, cls, show, lambda: bool(want) and received >= want,
                                   timeout, 10, qos, raw=False)
            if not received_all and timeout and received < max(want, 1):
                raise RosToolError(f"{received} message{'' if received == 1 else 's'} on {topic} within "
                                   f"{timeout:g} s{f', {want} asked' if want else ''}", 1)


def _listen(graph: _Graph, stop: _Stop, topic: str, cls: Any, callback: Callable[[Any], None],
            done: Callable[[], bool], timeout: float, depth: int, reliability: Reliability | None, raw: bool,
            tick: Callable[[], None] | None = None) -> bool:
    """Subscribe to ``topic`` once it has a publisher (with a QoS matching theirs) and spin until ``done()``,
    a signal or ``timeout`` [s] (0: none); ``tick`` is called between callbacks. Whether ``done()`` ended it."""
    start = time.monotonic()
    subscription = None
    told = False
    while not stop.now:
        if subscription is None:
            publishers = graph.publishers(topic)
            if publishers:
                subscription = graph.node.create_subscription(cls, topic, callback,
                                                              _qos(publishers, depth, reliability), raw=raw)
            elif not told and time.monotonic() - start > 1.0:
                err.print(f"sigcore ros: {topic} has no publisher yet; waiting")
                told = True
        graph.executor.spin_once(timeout_sec=0.05)
        if done():
            return True
        if tick is not None:
            tick()
        if timeout and time.monotonic() - start >= timeout:
            return False
    return False


# ---------------------------------------------------------------------- hz
@dataclass
class RateStats:
    """The rate of arrivals in a window: ``ros2 topic hz``'s figures."""

    rate: float
    min: float
    max: float
    std: float
    window: int

    def __str__(self) -> str:
        return (f"average rate: {self.rate:.3f}\n\tmin: {self.min:.3f}s max: {self.max:.3f}s std dev: "
                f"{self.std:.5f}s window: {self.window}")


def rate_stats(stamps: list[float]) -> RateStats | None:
    """Rate statistics of arrival times ``stamps`` [s]; None with fewer than two."""
    if len(stamps) < 2:
        return None
    periods = [b - a for a, b in zip(stamps, stamps[1:], strict=False)]
    mean = statistics.fmean(periods)
    return RateStats(1.0 / mean if mean > 0 else math.inf, min(periods), max(periods), statistics.pstdev(periods),
                     len(stamps))


@ros_app.command("hz")
def hz_command(
    topic: Annotated[str, typer.Argument(help="the topic")],
    window: Annotated[int, typer.Option("--window", "-w", min=2, help="statistics over the last N messages")]
        = 10000,
    duration: Annotated[float, typer.Option("--duration", "-d", min=0, help="stop after this long (seconds) (exit 1 if "
                                            "fewer than two messages came); 0: until Ctrl-C")] = 0.0,
    qos: Annotated[Reliability | None, typer.Option("--qos", help="subscribe reliable or best_effort (default: "
                                                    "reliable only if every publisher is)")] = None,
    wait: Annotated[float, typer.Option("--wait", min=0, help="how long the topic may take to appear on the "
                                        "graph (seconds)")] = DISCOVERY_WAIT,
) -> None:
    """A topic's average rate and the min, max and standard deviation of its period, every second, like
    `ros2 topic hz` (which does the same where ROS 2 is installed). Messages are not deserialized."""
    with _command("hz"):
        topic = _full_name(topic)
        _hz(topic, window, duration, qos, wait)


def _hz(topic: str, window: int, duration: float, qos: Reliability | None, wait: float) -> None:
    with _Graph("hz") as graph:
        stop = graph.stop
        cls = interface_class(graph.topic_type(topic, wait))
        stamps: deque[float] = deque(maxlen=window)
        state = {"total": 0, "printed": 0, "next": time.monotonic() + 1.0}

        def arrived(_data: bytes) -> None:
            stamps.append(time.monotonic())
            state["total"] += 1

        def tick() -> None:
            if time.monotonic() < state["next"]:
                return
            state["next"] += 1.0
            if state["total"] == state["printed"]:
                if state["total"]:
                    print("no new messages", flush=True)
                return
            stats = rate_stats(list(stamps))
            if stats is not None:
                print(stats, flush=True)
                state["printed"] = state["total"]

        _listen(graph, stop, topic, cls, arrived, lambda: False, duration, 100, qos, raw=True, tick=tick)
        if state["total"] != state["printed"] and (stats := rate_stats(list(stamps))) is not None:
            print(stats, flush=True)
        if state["total"] < 2:
            spent = f"in {duration:g} s" if duration and not stop.now else "before it was stopped"
            raise RosToolError(f"{'no message' if not state['total'] else 'only one message'} on {topic} {spent}: "
                               "no rate", 1)


# ---------------------------------------------------------------------- call
def parse_request(text: str) -> dict[str, Any]:
    """The YAML mapping of a request (empty text: no field set).

    Raises:
        RosToolError: malformed YAML (its error and where) or not a mapping.
    """
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise RosToolError(f"the request is not valid YAML: {problem}{where}: {quote(text)}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise RosToolError(f"the request must be a YAML mapping of fields, e.g. '{{data: true}}', not "
                           f"{quote(text)}")
    return data


@ros_app.command("call")
def call_command(
    service: Annotated[str, typer.Argument(help="the service, e.g. /sigcore/set_flag")],
    request: Annotated[str, typer.Argument(help="the request's fields as a YAML mapping, e.g. '{data: true}' or "
                                           "'{pose: {position: {x: 1.0}}}'")] = "{}",
    timeout: Annotated[float, typer.Option("--timeout", min=0, help="wait this long for the response (seconds) "
                                           "(exit 1 without one)")] = 5.0,
    wait: Annotated[float, typer.Option("--wait", min=0, help="how long the service may take to appear on the "
                                        "graph (seconds)")] = DISCOVERY_WAIT,
) -> None:
    """Call a service once and print its response as YAML. The type comes from the graph; the request is filled
    from the YAML mapping (fields not given keep their defaults). Where ROS 2 is installed, `ros2 service call`
    does the same."""
    with _command("call"):
        service = _full_name(service, service=True)
        values = parse_request(request)
        with _Graph("call") as graph:
            stop = graph.stop
            types, found = graph.wait_for(graph.services, service, wait)
            if types is None:
                raise RosToolError(f"service {service} is not on the ROS 2 graph ({_domain()}, after {wait:g} s)"
                                   f"{_listing(service, found, 'services')}")
            if len(types) != 1:
                raise RosToolError(f"service {service} has several types ({', '.join(types)}); cannot choose one")
            cls = interface_class(types[0], "srv")
            message = fill(checked(cls.Request), values, "request")
            client = graph.node.create_client(cls, service)
            start = time.monotonic()
            while not client.service_is_ready():
                if stop.now:
                    raise typer.Exit(1)
                if time.monotonic() - start >= timeout:
                    raise RosToolError(f"the server of {service} did not answer discovery within {timeout:g} s", 1)
                graph.spin(0.05)
            future = client.call_async(message)
            while not future.done():
                if stop.now:
                    raise typer.Exit(1)
                if time.monotonic() - start >= timeout:
                    raise RosToolError(f"no response from {service} within {timeout:g} s", 1)
                graph.executor.spin_once(timeout_sec=0.05)
            sys.stdout.write(to_yaml(future.result(), YamlStyle(truncate=0)))
            sys.stdout.flush()


# ---------------------------------------------------------------------- record
def _search_dirs() -> list[Path]:
    """Where interface sources are looked for: the source tree's ``interfaces/``, then the ``share/`` of each
    prefix (``AMENT_PREFIX_PATH``, this environment's)."""
    import sigcore

    dirs = [Path(sigcore.__file__).resolve().parent.parent / "interfaces"]
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p] + [sys.prefix]
    dirs += [Path(p) / "share" for p in prefixes]
    return dirs


def _message_file(typename: str) -> Path | None:
    package, kind, name = typename.split("/")
    for d in _search_dirs():
        path = d / package / kind / f"{name}.msg"
        if path.is_file():
            return path
    return None


def definition(serializer: Any, typename: str) -> tuple[str, str]:
    """``(ros2msg definition, RIHS01 hash)`` of ``typename`` from ``serializer``
    (:class:`sigcore.record.serialize.Serializer`); a type it does not know (``sigcore_msgs``,
    ``simulation_interfaces``, ...) is registered first from its ``.msg`` files, with those of the types it uses.

    Raises:
        RosToolError: no ``.msg`` file of the type (or of a type it uses), or one rosbags cannot parse.
    """
    from rosbags.interfaces import Nodetype
    from rosbags.typesys import get_types_from_msg

    from sigcore.record.exceptions import SerializeError

    if not serializer.knows(typename):
        found: dict[str, Any] = {}
        todo = [typename]
        while todo:
            name = todo.pop()
            if name in found or serializer.knows(name):
                continue
            path = _message_file(name)
            if path is None:
                raise RosToolError(f"no definition of {name} (no {name.split('/')[-1]}.msg in "
                                   f"{', '.join(str(d) for d in _search_dirs())})")
            try:
                types = get_types_from_msg(path.read_text(), name)
            except Exception as e:  # rosbags' TypesysError, a file that cannot be read
                raise RosToolError(f"{path} cannot be parsed ({type(e).__name__}: {e})") from None
            found.update(types)
            for _, fields in types.values():
                for _, desc in fields:
                    while desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE):
                        desc = desc[1][0]
                    if desc[0] == Nodetype.NAME:
                        todo.append(desc[1])
        serializer.register_types(found)
    try:
        result: tuple[str, str] = serializer.definition(typename)
    except SerializeError as e:
        raise RosToolError(str(e)) from None
    return result


@dataclass
class _Recorded:
    topic: Any
    subscription: Any
    typename: str


@ros_app.command("record")
def record_command(
    path: Annotated[Path, typer.Argument(help="the bag directory to create")],
    topics: Annotated[list[str] | None, typer.Argument(help="topics to record (recorded once they have a "
                                                      "publisher)")] = None,
    all_topics: Annotated[bool, typer.Option("--all", "-a", help="every topic (hidden ones left out), those that "
                                             "appear later too")] = False,
    regex: Annotated[list[str] | None, typer.Option("--regex", "-e", help="topics (not hidden) a regular "
                                                    "expression matches (re.search on the full name); repeatable")]
        = None,
    duration: Annotated[float, typer.Option("--duration", "-d", min=0, help="stop after this long (seconds); 0: until "
                                            "Ctrl-C or SIGTERM")] = 0.0,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="replace DIR if it holds a recording")] = False,
    use_sim_time: Annotated[bool, typer.Option("--use-sim-time", help="log messages at the latest /clock time "
                                               "instead of the wall clock")] = False,
    wait: Annotated[float, typer.Option("--wait", min=0, help="read the graph every 0.1 s this long at the start "
                                        "(then every second) (seconds)")] = DISCOVERY_WAIT,
) -> None:
    """Record topics received over DDS into a rosbag2 directory (MCAP storage), the bytes as they came, logged at
    their receive time; topics appearing later are picked up (the graph is re-read every second). Ctrl-C, SIGTERM or
    --duration end it and close the bag. Where ROS 2 is installed, `ros2 bag record` does the same."""
    with _command("record"):
        explicit = [_full_name(t) for t in topics or []]
        patterns = []
        for text in regex or []:
            try:
                patterns.append(re.compile(text))
            except re.error as e:
                raise RosToolError(f"--regex {quote(text)} is not a regular expression: {e}") from None
        if not (explicit or all_topics or patterns):
            raise RosToolError("nothing to record: name topics, or give --all or --regex")
        from sigcore.record.bag import BagWriter
        from sigcore.record.exceptions import BagError
        from sigcore.record.serialize import Serializer

        with _Graph("record") as graph:
            stop = graph.stop
            try:
                writer = BagWriter(path, overwrite)
            except BagError as e:
                raise RosToolError(str(e)) from None
            try:
                recorded = _record(graph, stop, writer, Serializer(), explicit, all_topics, patterns, duration,
                                   use_sim_time, wait)
            finally:
                writer.close()
        _summary(path, writer, recorded, explicit)
        if writer.failure:
            raise RosToolError(writer.failure, 1)


def _record(graph: _Graph, stop: _Stop, writer: Any, serializer: Any, explicit: list[str], all_topics: bool,
            patterns: list[re.Pattern[str]], duration: float, use_sim_time: bool, wait: float
            ) -> dict[str, _Recorded]:
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from sigcore.publish import Offered

    recorded: dict[str, _Recorded] = {}
    refused: set[str] = set()
    clock = {"ns": -1}
    pending: list[tuple[Any, bytes]] = []
    dropped = 0

    def stamp() -> int:
        return clock["ns"] if use_sim_time else time.time_ns()

    def receiver(topic: Any) -> Callable[[bytes], None]:
        def received(data: bytes) -> None:
            nonlocal dropped
            if use_sim_time and clock["ns"] < 0:
                if len(pending) < PENDING_LIMIT:
                    pending.append((topic, data))
                else:
                    dropped += 1
                return
            writer.write(topic, stamp(), data)
        return received

    if use_sim_time:
        from rosgraph_msgs.msg import Clock

        def ticked(msg: Any) -> None:
            clock["ns"] = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec
            for topic, data in pending:
                writer.write(topic, clock["ns"], data)
            pending.clear()

        graph.node.create_subscription(Clock, "/clock", ticked,
                                       QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))

    def refuse(name: str, why: str) -> None:
        refused.add(name)
        err.print(f"sigcore ros record: warning: not recording {name}: {why}")

    def scan() -> None:
        for name, types in graph.topics(hidden=True).items():
            if name in recorded or name in refused:
                continue
            if not (name in explicit or (not _hidden(name) and (all_topics or any(p.search(name) for p in patterns)))):
                continue
            publishers = graph.publishers(name)
            if not publishers:
                continue  # recorded once a publisher shows its QoS
            if len(types) != 1:
                refuse(name, f"it has several types ({', '.join(types)})")
                continue
            typename = types[0]
            try:
                cls = interface_class(typename)
                text, digest = definition(serializer, typename)
            except RosToolError as e:
                refuse(name, str(e))
                continue
            offered_hash = str(publishers[0].topic_type_hash)
            if offered_hash.startswith("RIHS01_") and offered_hash != digest:
                err.print(f"sigcore ros record: warning: {name}: the definition of {typename} found here hashes to "
                          f"{digest}, its publisher's type to {offered_hash}; the bag keeps the publisher's")
                digest = offered_hash
            qos = _qos(publishers, RECORD_DEPTH)
            depths = [p.qos_profile.depth for p in publishers if p.qos_profile.depth > 0]
            offered = Offered(max(depths) if depths else UNKNOWN_DEPTH,
                              qos.reliability == ReliabilityPolicy.RELIABLE,
                              qos.durability == DurabilityPolicy.TRANSIENT_LOCAL)
            topic = writer.add_topic(name, typename, text, digest, offered)
            if topic is None:  # the writer stopped (a failed write)
                stop.now = True
                return
            subscription = graph.node.create_subscription(cls, name, receiver(topic), qos, raw=True)
            recorded[name] = _Recorded(topic, subscription, typename)
            print(f"recording {name} [{typename}]", flush=True)

    start = time.monotonic()
    next_scan = start
    while not stop.now and writer.active:
        now = time.monotonic()
        if duration and now - start >= duration:
            break
        if now >= next_scan:
            scan()
            next_scan = now + (0.1 if now - start < wait else RESCAN_PERIOD)
        graph.executor.spin_once(timeout_sec=0.05)
    if pending or dropped:
        err.print(f"sigcore ros record: warning: {len(pending) + dropped} messages received before the first /clock "
                  "were not recorded")
    return recorded


def _summary(path: Path, writer: Any, recorded: dict[str, _Recorded], explicit: list[str]) -> None:
    total = sum(r.topic.count for r in recorded.values())
    print(f"recorded {path}: {total} message{'' if total == 1 else 's'} on {len(recorded)} "
          f"topic{'' if len(recorded) == 1 else 's'}", flush=True)
    width = max((len(n) for n in recorded), default=0)
    for name in sorted(recorded):
        r = recorded[name]
        print(f"  {name:<{width}}  {r.topic.count:>7}  {r.typename}", flush=True)
    missing = [t for t in explicit if t not in recorded]
    if missing:
        err.print(f"sigcore ros record: warning: never recorded (no publisher seen, or refused above): "
                  f"{', '.join(missing)}")
