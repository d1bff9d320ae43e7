"""Wait for the simulation's latched readiness signal (shared by the examples)."""

import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Bool


def wait_ready(node: Node, timeout: float = 60.0) -> None:
    """Block until /sigcore/ready is true (it is latched: transient local)."""
    got = []
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    sub = node.create_subscription(Bool, "/sigcore/ready", lambda m: got.append(m.data), qos)
    end = node.get_clock().now().nanoseconds + int(timeout * 1e9)
    while not (got and got[-1]):
        rclpy.spin_once(node, timeout_sec=0.1)
        if node.get_clock().now().nanoseconds > end:
            raise TimeoutError("no simulation announced /sigcore/ready")
    node.destroy_subscription(sub)
