"""A plain rclpy node for the ``sigcore ros`` tests (no sigcore import): topics and services to introspect.

- ``/peer/seq`` (``std_msgs/msg/UInt32``, reliable, volatile): 1, 2, 3, ... at 20 Hz;
- ``/peer/point`` (``geometry_msgs/msg/PointStamped``): always the same message, at 5 Hz;
- ``/peer/latched`` (``std_msgs/msg/String``, transient local, depth 1): "latched hello", published once at the start;
- ``/peer/best_effort`` (``std_msgs/msg/String``, best effort): "best effort hello" at 5 Hz;
- ``/peer/recv`` (``sigcore_msgs/msg/OnRecvMsg``, a type rosbags does not know): sender "peer", content the count, at
  5 Hz;
- ``/peer/cmd`` (``std_msgs/msg/String``): a subscription, nobody publishes it;
- ``/peer/set_flag`` (``std_srvs/srv/SetBool``): success = data, message "flag set to true|false";
- ``/peer/set_state`` (``simulation_interfaces/srv/SetEntityState``): answers with the entity and the position it got;
- ``/peer/slow`` (``std_srvs/srv/Trigger``): answers after 4 s (the whole node waits meanwhile).

Prints ``{"ready": true}`` once everything exists; on SIGINT or SIGTERM stops publishing, goes on spinning for 0.5 s
(so the last messages are delivered), prints ``{"seq": <last /peer/seq sent>}`` and exits.
"""

from __future__ import annotations

import json
import signal
import time

import rclpy
from geometry_msgs.msg import PointStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from sigcore_msgs.msg import OnRecvMsg
from simulation_interfaces.srv import SetEntityState
from std_msgs.msg import String, UInt32
from std_srvs.srv import SetBool, Trigger

rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
node = rclpy.create_node("tools_peer")
seq_pub = node.create_publisher(UInt32, "/peer/seq", QoSProfile(depth=10))
point_pub = node.create_publisher(PointStamped, "/peer/point", QoSProfile(depth=10))
latched_pub = node.create_publisher(String, "/peer/latched",
                                    QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
best_pub = node.create_publisher(String, "/peer/best_effort",
                                 QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT))
recv_pub = node.create_publisher(OnRecvMsg, "/peer/recv", QoSProfile(depth=10))
node.create_subscription(String, "/peer/cmd", lambda _msg: None, QoSProfile(depth=10))

state = {"seq": 0, "slow": 0, "stop": False}


def set_flag(request: SetBool.Request, response: SetBool.Response) -> SetBool.Response:
    response.success = request.data
    response.message = f"flag set to {str(request.data).lower()}"
    return response


def set_state(request: SetEntityState.Request, response: SetEntityState.Response) -> SetEntityState.Response:
    p = request.state.pose.position
    response.result.result = 1
    response.result.error_message = f"{request.entity} at {p.x:g} {p.y:g} {p.z:g} in {request.state.header.frame_id}"
    return response


node.create_service(SetBool, "/peer/set_flag", set_flag)
node.create_service(SetEntityState, "/peer/set_state", set_state)


def slow_answer(_request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
    time.sleep(4.0)
    response.success = True
    return response


node.create_service(Trigger, "/peer/slow", slow_answer)


def fast() -> None:
    state["seq"] += 1
    seq_pub.publish(UInt32(data=state["seq"]))


def slow() -> None:
    state["slow"] += 1
    point = PointStamped()
    point.header.stamp.sec, point.header.stamp.nanosec, point.header.frame_id = 12, 345, "peer_frame"
    point.point.x, point.point.y, point.point.z = 1.5, -2.0, 0.25
    point_pub.publish(point)
    best_pub.publish(String(data="best effort hello"))
    recv_pub.publish(OnRecvMsg(sender="peer", content=str(state["slow"])))


latched_pub.publish(String(data="latched hello"))
timers = [node.create_timer(0.05, fast), node.create_timer(0.2, slow)]


def stop(*_: object) -> None:
    state["stop"] = True


signal.signal(signal.SIGINT, stop)
signal.signal(signal.SIGTERM, stop)
executor = SingleThreadedExecutor()
executor.add_node(node)
print(json.dumps({"ready": True}), flush=True)
while not state["stop"]:
    executor.spin_once(timeout_sec=0.05)
for timer in timers:
    timer.cancel()
end = time.monotonic() + 0.5
while time.monotonic() < end:
    executor.spin_once(timeout_sec=0.05)
print(json.dumps({"seq": state["seq"]}), flush=True)
node.destroy_node()
rclpy.try_shutdown()
