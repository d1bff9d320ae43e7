#!/usr/bin/env python3
"""The moderator as a ROS 2 user writes it: plain rclpy (successor of sig_ros's ModeratorCommand).

It connects ``moderator_0`` to the referee service (``moderator_0_connect_to_service``, ``_check_service``), watches
the robot's collisions (``robot_000_onCollisionMsg``) and reports each collision with furniture or a wall to the
referee with ``moderator_0_send_msg_to_srv`` as ``Referee/<text>/<points>``. The referee's clean-up rules already
count collision penalties themselves, so the moderator reports with 0 points by default (``--points -100`` to
penalise like the original, when the world's referee runs without rules).

It also follows the referee's topics, which any node can read: ``/referee/score`` (std_msgs/Int32, latched: the
current total), ``/referee/events`` (sigcore_msgs/RefereeEvent: each scored event with its time, kind, points and
the total after it) and ``/referee/result`` (sigcore_msgs/RefereeResult, latched: the result and the score table
once the task has ended). With ``--log FILE`` it writes what it received as JSON when the result arrives.

Run (with the simulator running ``--transport ros2``):  python examples/cleanup/moderator_node.py
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sigcore_msgs.msg import OnCollisionMsg, RefereeEvent, RefereeResult
from sigcore_msgs.srv import CheckService, ConnectToService, SendMsgToSrv
from std_msgs.msg import Int32

ME, ROBOT = "moderator_0", "robot_000"
OBSTACLES = ("wall_", "table_", "wagon")


class Moderator(Node):
    """Reports the robot's collisions with obstacles to the referee."""

    def __init__(self, points: int, log: str | None = None) -> None:
        super().__init__("cleanup_moderator")
        self.points = points
        self.log = log
        self.received: dict = {"scores": [], "events": [], "result": None}
        self.done = False
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.create_subscription(Int32, "/referee/score", self.on_score, latched)
        self.create_subscription(RefereeEvent, "/referee/events", self.on_event, 50)
        self.create_subscription(RefereeResult, "/referee/result", self.on_result, latched)
        self.check = self.create_client(CheckService, f"{ME}_check_service")
        self.connect = self.create_client(ConnectToService, f"{ME}_connect_to_service")
        self.send = self.create_client(SendMsgToSrv, f"{ME}_send_msg_to_srv")
        self.create_subscription(OnCollisionMsg, f"{ROBOT}_onCollisionMsg", self.on_collision, 50)
        self.reported = 0
        self.spinner = SingleThreadedExecutor()  # as robot_node.py: not rclpy's busy spin_until_future_complete
        self.spinner.add_node(self)

    def call(self, client, request):  # type: ignore[no-untyped-def]
        if not client.wait_for_service(timeout_sec=30.0):
            raise RuntimeError(f"service {client.srv_name} is not available")
        future = client.call_async(request)
        deadline = time.monotonic() + 10.0
        while not future.done():
            if time.monotonic() > deadline or not rclpy.ok():
                raise RuntimeError(f"{client.srv_name} did not answer")
            self.spinner.spin_once(timeout_sec=0.1)
        return future.result()

    def connect_referee(self) -> None:
        r = self.call(self.connect, ConnectToService.Request(service_name="referee"))
        if not r.connected:  # e.g. "no service 'referee'; services: none": enable <plugin name="referee"/>
            raise RuntimeError(f"cannot connect to the referee: {r.message}")
        connected = self.call(self.check, CheckService.Request(service_name="referee")).connected
        self.get_logger().info(f"connected to the referee: {connected}")

    def on_score(self, msg: Int32) -> None:
        self.received["scores"].append(msg.data)
        self._update()

    def on_event(self, msg: RefereeEvent) -> None:
        self.received["events"].append({"time": msg.time, "kind": msg.kind, "text": msg.text,
                                        "points": msg.points, "score": msg.score})
        self.get_logger().info(f"referee: {msg.kind} {msg.points:+d} ({msg.text}), score {msg.score}")
        self._update()

    def on_result(self, msg: RefereeResult) -> None:
        self.received["result"] = {"result": msg.result, "score": msg.score, "time": msg.time,
                                   "report": list(msg.report)}
        self.get_logger().info(f"referee result: {msg.result}, score {msg.score} after {msg.time:.1f} s")
        self._update()

    def _update(self) -> None:
        """Write what was received (if asked); done once the result and the final `end` event are both in (they come
        on different topics, in either order)."""
        if self.log:
            with open(self.log, "w") as f:
                json.dump(self.received, f, indent=1)
        events = self.received["events"]
        if self.received["result"] is not None and events and events[-1]["kind"] == "end":
            self.done = True  # the task has ended: nothing left to moderate

    def on_collision(self, msg: OnCollisionMsg) -> None:
        if msg.name.startswith(OBSTACLES):
            text = f"Referee/{ROBOT} ({msg.part}) collided with {msg.name}/{self.points}"
            future = self.send.call_async(SendMsgToSrv.Request(name="referee", msg=text))
            future.add_done_callback(lambda f: self.get_logger().info(f"reported: {text} -> {f.result().ok}"))
            self.reported += 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=0, help="points per reported collision")
    ap.add_argument("--log", default=None, help="write the referee's score, events and result here (JSON)")
    args = ap.parse_args()
    rclpy.init()
    node = Moderator(args.points, args.log)
    try:
        node.connect_referee()
        while rclpy.ok() and not node.done:
            node.spinner.spin_once(timeout_sec=0.5)
        return 0
    except RuntimeError as e:
        node.get_logger().error(str(e))
        return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
