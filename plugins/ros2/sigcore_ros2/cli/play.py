"""``sigcore bag play DIR``: a recording published on ROS 2 at its simulated pace (times a rate factor), with /clock.

Each recorded topic gets a publisher of its type offered with the QoS it was recorded with (so ``/tf_static``,
``robot_description`` and ``/map`` are latched again); the recorded bytes are published as they are. /clock is the
player's own: the log time of the next message before that message goes out (a node with ``use_sim_time`` never sees
a message ahead of its clock), and at ``--clock-rate`` per second of wall time in between; the recording's own
``/clock``, if it has one, is not replayed. Where ROS 2 is installed, ``ros2 bag play DIR --clock`` does the same.
"""

from __future__ import annotations

import re
import signal
import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

from .messages import message_class

err = Console(stderr=True, highlight=False, markup=False, soft_wrap=True)
out = Console(highlight=False, markup=False, soft_wrap=True)


def _class_or_none(typename: str) -> Any:
    """The rclpy class of ``pkg/msg/Name``, or None when its package is not installed."""
    try:
        return message_class(typename)
    except (ImportError, AttributeError):
        return None


def play_command(
    path: Annotated[Path, typer.Argument(help="a recording: its directory (or one .mcap file)")],
    rate: Annotated[float, typer.Option("--rate", "-r", min=0.001, help="pace: a factor of the recorded (simulated) "
                                        "time; 1 = as recorded")] = 1.0,
    loop: Annotated[bool, typer.Option("--loop", "-l", help="start again at the end, until interrupted")] = False,
    topics: Annotated[list[str] | None, typer.Option(
        "--topics", metavar="REGEX", help="only the topics a regular expression matches (re.search); repeatable")]
        = None,
    clock_rate: Annotated[float, typer.Option(
        "--clock-rate", min=0, help="/clock messages per second of wall time between messages [Hz]; 0: no /clock")]
        = 100.0,
    delay: Annotated[float, typer.Option(
        "--delay", min=0, help="wait this long after creating the publishers, so subscribers discover them [s]")]
        = 1.0,
    wait_for: Annotated[list[str] | None, typer.Option(
        "--wait-for", metavar="TOPIC", help="before playing, wait until TOPIC (a played topic or /clock) has a "
        "subscriber; repeatable")] = None,
    wait_timeout: Annotated[float, typer.Option(
        "--wait-timeout", min=0, help="with --wait-for: play anyway after this long, with a warning [s]")] = 30.0,
) -> None:
    """Publish a recording on ROS 2 with /clock, at its simulated pace times --rate; --loop repeats it. Where ROS 2
    is installed, ros2 bag play DIR --clock does the same."""
    from sigcore.record.bag_reading import bag_info, iter_messages
    from sigcore.record.exceptions import BagError

    patterns = []
    for text in topics or []:
        try:
            patterns.append(re.compile(text))
        except re.error as e:
            err.print(f"sigcore bag play: --topics {text!r} is not a regular expression: {e}")
            raise typer.Exit(2) from None
    try:
        info = bag_info(path)
    except BagError as e:
        err.print(f"sigcore bag play: {e}")
        raise typer.Exit(2) from None
    for problem in info.problems:
        err.print(f"sigcore bag play: warning: {problem}; playing what is readable")
    own_clock = clock_rate > 0
    chosen = [t for t in info.topics if (not patterns or any(p.search(t.name) for p in patterns))
              and not (own_clock and t.name == "/clock")]
    if not chosen:
        err.print(f"sigcore bag play: no topic of {path} to play; it has: "
                  f"{', '.join(sorted(t.name for t in info.topics)) or 'none'}")
        raise typer.Exit(2)
    try:
        import rclpy
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
    except ImportError as e:
        err.print(f"sigcore bag play: rclpy cannot be imported ({e}); run scripts/setup.sh")
        raise typer.Exit(2) from None

    rclpy.init(args=[])
    node = rclpy.create_node("sigcore_bag_play")
    publishers: dict[str, Any] = {}
    skipped: list[str] = []
    for t in chosen:
        cls = _class_or_none(t.typename)
        if cls is None:
            skipped.append(f"{t.name} ({t.typename}: its package is not installed)")
            continue
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=max(1, t.offered.depth),
                         reliability=ReliabilityPolicy.RELIABLE if t.offered.reliable
                         else ReliabilityPolicy.BEST_EFFORT,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL if t.offered.latched
                         else DurabilityPolicy.VOLATILE)
        publishers[t.name] = node.create_publisher(cls, t.name, qos)
    for s in skipped:
        err.print(f"sigcore bag play: not played: {s}")
    clock = node.create_publisher(Clock, "/clock", QoSProfile(depth=1)) if own_clock else None
    waits = []
    for topic in wait_for or []:
        pub = clock if topic == "/clock" else publishers.get(topic)
        if pub is None:
            err.print(f"sigcore bag play: --wait-for {topic}: not a topic it plays; it plays: "
                      f"{', '.join(sorted(publishers) + (['/clock'] if clock is not None else []))}")
            node.destroy_node()
            rclpy.try_shutdown()
            raise typer.Exit(2)
        waits.append((topic, pub))
    stop = {"now": False}

    def interrupted(*_: Any) -> None:
        stop["now"] = True

    previous = {sig: signal.signal(sig, interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    played = 0
    try:
        out.print(f"playing {path}: {len(publishers)} topics, {info.messages} messages, "
                  f"{(info.end_ns - info.start_ns) / 1e9:.3f} s at {rate:g}x{' (looping)' if loop else ''}")
        time.sleep(delay)
        deadline = time.monotonic() + wait_timeout
        for topic, pub in waits:
            while pub.get_subscription_count() < 1 and not stop["now"]:
                if time.monotonic() > deadline:
                    err.print(f"sigcore bag play: warning: {topic} has no subscriber after {wait_timeout:g} s; "
                              "playing anyway")
                    break
                time.sleep(0.02)
        while not stop["now"]:
            played += _play_once(info, publishers, clock, rate, clock_rate, stop, iter_messages)
            if not loop:
                break
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        time.sleep(0.2)  # let the last messages leave before the node goes
        node.destroy_node()
        rclpy.try_shutdown()
    out.print(f"played {played} messages{' (interrupted)' if stop['now'] else ''}")


def _play_once(info: Any, publishers: dict[str, Any], clock: Any, rate: float, clock_rate: float,
               stop: dict[str, bool], iter_messages: Any) -> int:
    """Publish the bag once at its pace; the number of messages published."""
    from rosgraph_msgs.msg import Clock

    sent = [-1]

    def tick(ns: int) -> None:
        if clock is not None and ns > sent[0]:  # /clock never goes back within one pass
            sent[0] = ns
            msg = Clock()
            msg.clock.sec, msg.clock.nanosec = divmod(ns, 1_000_000_000)
            clock.publish(msg)

    start_wall, start_ns = time.monotonic(), info.start_ns
    period = 1.0 / clock_rate if clock_rate > 0 else None
    last_tick = -1.0
    count = 0
    for topic, log_ns, data in iter_messages(info, publishers):
        due = start_wall + (log_ns - start_ns) / 1e9 / rate
        while not stop["now"]:
            now = time.monotonic()
            if now >= due:
                break
            if period is not None and now - last_tick >= period:  # /clock in between, at the recorded pace
                tick(start_ns + round((now - start_wall) * rate * 1e9))
                last_tick = now
            time.sleep(min(due - now, period or 0.05))
        if stop["now"]:
            break
        tick(log_ns)
        last_tick = time.monotonic()
        publishers[topic].publish(data)
        count += 1
    return count
