"""The topic commands: ``sigcore ros topics`` (the topics on the graph, with types and counts), ``sigcore ros echo``
(a topic's messages as YAML) and ``sigcore ros hz`` (a topic's rate, from raw messages), each in one hidden node."""

from __future__ import annotations

import math
import statistics
import sys
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any

import typer

from ..exceptions import RosToolError
from .console import command_errors, err
from .graph import DISCOVERY_WAIT, Graph, Reliability, Stop, domain, full_name, matching_qos
from .messages import interface_class
from .yamltext import TRUNCATE_LENGTH, YamlStyle, field_of, to_yaml

TOPICS_WAIT = 3.0
"""Default ``--wait`` of ``topics``: how long the graph is watched before it is listed [s] (see
:data:`~sigcore_ros2.cli.graph.DISCOVERY_WAIT`)."""
SETTLE = 0.5
"""``topics`` goes on waiting past ``--wait`` while the graph changed in the last ``SETTLE`` seconds [s]."""


# ---------------------------------------------------------------------- topics
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
    with command_errors("topics"), Graph("topics") as graph:
        found = _settled(graph, include_hidden, wait)
        if not found:
            err.print(f"sigcore ros topics: no topic on the ROS 2 graph ({domain()}) after {2 * wait:g} s")
            return
        for name in sorted(found):
            line = name
            if types:
                line += f" [{', '.join(found[name])}]"
            if counts:
                p, s = len(graph.publishers(name)), len(graph.subscribers(name))
                line += f" ({p} publisher{'' if p == 1 else 's'}, {s} subscriber{'' if s == 1 else 's'})"
            print(line, flush=True)


def _settled(graph: Graph, hidden: bool, wait: float) -> dict[str, list[str]]:
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
    with command_errors("echo"):
        topic = full_name(topic)
        want = 1 if once else count
        path = field.split(".") if field else []
        style = YamlStyle(truncate_length, no_arr, no_str)
        with Graph("echo") as graph:
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


def _listen(graph: Graph, stop: Stop, topic: str, cls: Any, callback: Callable[[Any], None],
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
                                                              matching_qos(publishers, depth, reliability), raw=raw)
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
    with command_errors("hz"):
        topic = full_name(topic)
        _hz(topic, window, duration, qos, wait)


def _hz(topic: str, window: int, duration: float, qos: Reliability | None, wait: float) -> None:
    with Graph("hz") as graph:
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
