"""Sends a simulate_steps goal of 5 steps with an action client one of whose response readers can never match the
simulator's response writer (transient-local durability asked, volatile offered), for real: with ``result`` (the
default) the get_result reader, so the goal is accepted and runs and its result cannot be delivered; with ``goal``
the send_goal reader, so the goal arrives and its acceptance cannot be delivered. Waits until a plain client of the
same node is matched with the server (at most 60 s: discovery is slow on a loaded machine), sends the goal, asks for
the result once accepted, and spins until a line comes on stdin or 60 s passed; prints whether the goal was accepted
(null: no answer) and whether a result came (JSON)."""

from __future__ import annotations

import json
import select
import sys
import time

import rclpy
from rclpy.action import ActionClient
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from simulation_interfaces.action import SimulateSteps

rclpy.init()
node = rclpy.create_node("unmatched_result")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
unmatched = sys.argv[1] if len(sys.argv) > 1 else "result"
client = ActionClient(node, SimulateSteps, "/simulate_steps", **{f"{unmatched}_service_qos_profile": qos})
# wait_for_server would wait in vain (one service never matches), and a goal sent when the graph shows the server
# can be lost (this client's goal request writer is not matched yet: seen under load). A plain client of the same node
# (one DDS participant) waits for the server: once it is matched the server's endpoints are known to the participant,
# and this client's goal request writer is matched with the reader too (at most 60 s: discovery on a loaded machine).
probe = ActionClient(node, SimulateSteps, "/simulate_steps")
deadline = time.monotonic() + 60.0
while time.monotonic() < deadline and not probe.server_is_ready():
    rclpy.spin_once(node, timeout_sec=0.1)
rclpy.spin_once(node, timeout_sec=0.5)
out: dict[str, object] = {"accepted": None, "result": False}
goal_future = client.send_goal_async(SimulateSteps.Goal(steps=5))
end = time.monotonic() + 30.0
while time.monotonic() < end and not goal_future.done() and not select.select([sys.stdin], [], [], 0)[0]:
    rclpy.spin_once(node, timeout_sec=0.1)
handle = goal_future.result() if goal_future.done() else None
out["accepted"] = None if handle is None else bool(handle.accepted)
result_future = handle.get_result_async() if handle is not None and handle.accepted else None
print("asked", flush=True)
end = time.monotonic() + 60.0
while time.monotonic() < end and not select.select([sys.stdin], [], [], 0)[0]:
    rclpy.spin_once(node, timeout_sec=0.1)
out["result"] = result_future is not None and result_future.done()
print(json.dumps(out), flush=True)
