"""``sigcore ros record DIR``: a rosbag2 directory (MCAP) of topics received over DDS, written by
:class:`sigcore.record.bag.BagWriter` with the bytes as they came; a topic's definition and hash come from the
serializer, or from the ``.msg`` files of a type it does not know."""

from __future__ import annotations

import os
import re
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer

from sigcore.text import quote

from ..exceptions import RosToolError
from .console import command_errors, err
from .graph import DISCOVERY_WAIT, Graph, Stop, full_name, is_hidden, matching_qos
from .messages import interface_class

RESCAN_PERIOD = 1.0
"""``record`` re-reads the graph this often for new topics [s] (every 0.1 s during its first ``--wait``)."""
RECORD_DEPTH = 100
"""Depth of the recorder's subscriptions (messages waiting to be written) [messages]."""
UNKNOWN_DEPTH = 10
"""The depth written as a topic's offered QoS when the graph does not tell the publishers' (remote DDS endpoints
never tell their history depth)."""
PENDING_LIMIT = 10_000
"""``record --use-sim-time``: at most this many messages received before the first /clock are kept [messages]."""


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
    with command_errors("record"):
        explicit = [full_name(t) for t in topics or []]
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

        with Graph("record") as graph:
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


def _record(graph: Graph, stop: Stop, writer: Any, serializer: Any, explicit: list[str], all_topics: bool,
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
            wanted = not is_hidden(name) and (all_topics or any(p.search(name) for p in patterns))
            if not (name in explicit or wanted):
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
            qos = matching_qos(publishers, RECORD_DEPTH)
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
