#!/usr/bin/env python3
"""The moderator as a ROS 2 user writes it: plain rclpy (successor of sig_ros's ModeratorCommand).

It connects ``moderator_0`` to the referee service (``moderator_0_check_service``, ``_connect_to_service``), watches
the robot's collisions (``robot_000_onCollisionMsg``) and reports each collision with furniture or a wall to the
referee with ``moderator_0_send_msg_to_srv`` as ``Referee/<text>/<points>``. The referee's clean-up rules already
count collision penalties themselves, so the moderator reports with 0 points by default (``--points -100`` to
penalise like the original, when the world's referee runs without rules).

Run (with the simulator running ``--transport ros2``):  python examples/cleanup/moderator_node.py
"""

from __future__ import annotations

import argparse
import sys

import rclpy
from rclpy.node import Node
from sigcore_msgs.msg import OnCollisionMsg
from sigcore_msgs.srv import CheckService, ConnectToService, SendMsgToSrv

ME, ROBOT = "moderator_0", "robot_000"
OBSTACLES = ("wall_", "table_", "wagon")


class Moderator(Node):
    """Reports the robot's collisions with obstacles to the referee."""

    def __init__(self, points: int) -> None:
        super().__init__("cleanup_moderator")
        self.points = points
        self.check = self.create_client(CheckService, f"{ME}_check_service")
        self.connect = self.create_client(ConnectToService, f"{ME}_connect_to_service")
        self.send = self.create_client(SendMsgToSrv, f"{ME}_send_msg_to_srv")
        self.create_subscription(OnCollisionMsg, f"{ROBOT}_onCollisionMsg", self.on_collision, 50)
        self.reported = 0

    def call(self, client, request):  # type: ignore[no-untyped-def]
        if not client.wait_for_service(timeout_sec=30.0):
            raise RuntimeError(f"service {client.srv_name} is not available")
        future = client.call_async(request)
        rclpy.spin_until_future_complete(self, future, timeout_sec=10.0)
        return future.result()

    def connect_referee(self) -> None:
        if not self.call(self.check, CheckService.Request(service_name="referee")).connected:
            raise RuntimeError("no referee service in this world (enable <plugin name=\"referee\"/>)")
        r = self.call(self.connect, ConnectToService.Request(service_name="referee"))
        self.get_logger().info(f"connected to the referee: {r.connected}")

    def on_collision(self, msg: OnCollisionMsg) -> None:
        if msg.name.startswith(OBSTACLES):
            text = f"Referee/{ROBOT} ({msg.part}) collided with {msg.name}/{self.points}"
            future = self.send.call_async(SendMsgToSrv.Request(name="referee", msg=text))
            future.add_done_callback(lambda f: self.get_logger().info(f"reported: {text} -> {f.result().ok}"))
            self.reported += 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=0, help="points per reported collision")
    args = ap.parse_args()
    rclpy.init()
    node = Moderator(args.points)
    try:
        node.connect_referee()
        rclpy.spin(node)
        return 0
    except RuntimeError as e:
        node.get_logger().error(str(e))
        return 1
    except KeyboardInterrupt:
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
