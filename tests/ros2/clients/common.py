"""A plain rclpy client for the tests' client processes (no sigcore import): calls, publishes, listens.

Each client script prints one JSON object as its last line of output; the test reads it.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from typing import Any

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Bool


def setf(msg: Any, fields: dict[str, Any]) -> Any:
    """Set (nested, with dotted keys) fields of a ROS message; returns it."""
    for key, value in fields.items():
        target = msg
        *path, last = key.split(".")
        for p in path:
            target = getattr(target, p)
        setattr(target, last, value)
    return msg


def todict(msg: Any) -> Any:
    """A ROS message as plain JSON-able data."""
    if hasattr(msg, "get_fields_and_field_types"):
        return {k: todict(getattr(msg, k)) for k in msg.get_fields_and_field_types()}
    if isinstance(msg, list | tuple) or type(msg).__name__ == "array":
        return [todict(v) for v in msg]
    if hasattr(msg, "tolist"):
        return msg.tolist()
    return msg


class Client:
    """One node with an executor; every wait is bounded."""

    def __init__(self, name: str = "test_client") -> None:
        rclpy.init()
        self.node = rclpy.create_node(name)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._clients: dict[str, Any] = {}
        self._pubs: dict[str, Any] = {}

    def spin(self, seconds: float) -> None:
        """Process callbacks for ``seconds`` [s]."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))

    def wait_for(self, predicate: Callable[[], bool], timeout: float = 10.0) -> bool:
        """Spin until ``predicate()`` or ``timeout`` [s]."""
        end = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > end:
                return False
            self.executor.spin_once(timeout_sec=0.05)
        return True

    def wait_ready(self, timeout: float = 60.0) -> bool:
        """Wait for the simulation's latched readiness signal."""
        got: list[bool] = []
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
        sub = self.node.create_subscription(Bool, "/sigcore/ready", lambda m: got.append(m.data), qos)
        ok = self.wait_for(lambda: bool(got) and got[-1], timeout)
        self.node.destroy_subscription(sub)
        return ok

    def call(self, srv_type: Any, name: str, /, timeout: float = 10.0, **fields: Any) -> Any:
        """Call service ``name``; the response, or None on timeout."""
        cli = self._clients.get(name)
        if cli is None:
            cli = self._clients[name] = self.node.create_client(srv_type, name)
            if not cli.wait_for_service(timeout_sec=timeout):
                return None
        future = cli.call_async(setf(srv_type.Request(), fields))
        self.executor.spin_until_future_complete(future, timeout_sec=timeout)
        return future.result() if future.done() else None

    def publish(self, msg_type: Any, topic: str, /, **fields: Any) -> None:
        """Publish once on ``topic`` (after waiting up to 5 s for the simulation's subscription to match)."""
        pub = self._pubs.get(topic)
        if pub is None:
            pub = self._pubs[topic] = self.node.create_publisher(msg_type, topic, 10)
            self.wait_for(lambda: pub.get_subscription_count() > 0, 5.0)
            self.spin(0.3)  # the subscriber's side of the match may lag the publisher's: a first message
            # published right away could be lost (volatile durability)
        pub.publish(setf(msg_type(), fields))

    def listen(self, msg_type: Any, topic: str, qos: Any = 10) -> list[Any]:
        """Collect every message of ``topic`` into the returned list (filled while spinning)."""
        got: list[Any] = []
        self.node.create_subscription(msg_type, topic, got.append, qos)
        return got


    def graph(self, node: str = "sigcore") -> set[str]:
        """The topics and services of ``node`` (at the root namespace) as this client sees them now; empty while the
        node is not discovered yet."""
        n = self.node
        try:
            return ({t for t, _ in n.get_publisher_names_and_types_by_node(node, "/")}
                    | {t for t, _ in n.get_subscriber_names_and_types_by_node(node, "/")}
                    | {s for s, _ in n.get_service_names_and_types_by_node(node, "/")})
        except Exception:  # the node is not discovered yet
            return set()


def emit(result: Any) -> None:
    """Print the result as the last line (JSON) and exit."""
    sys.stdout.write(json.dumps(result) + "\n")
    sys.stdout.flush()
