"""Sends a simulate_steps goal of 5 steps with an action client whose get_result response reader can never match
the simulator's response writer (transient-local durability asked, volatile offered), while its goal service works:
the goal is accepted and runs, and its result cannot be delivered, for real. Waits for the goal service in the graph (at
most 60 s: discovery is slow on a loaded machine), sends the goal, asks for the result, and spins until a line comes on
stdin or 60 s passed; prints whether the goal was accepted and whether a result came (JSON)."""

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
client = ActionClient(node, SimulateSteps, "/simulate_steps", result_service_qos_profile=qos)
# wait_for_server would wait in vain (the result service never matches): wait for the goal service in the graph
deadline = time.monotonic() + 60.0
while time.monotonic() < deadline and not any(name == "/simulate_steps/_action/send_goal"
                                               for name, _ in node.get_service_names_and_types()):
    rclpy.spin_once(node, timeout_sec=0.1)
rclpy.spin_once(node, timeout_sec=0.5)  # the goal request writer matches the reader the graph just showed
out: dict[str, object] = {"accepted": None, "result": False}
goal_future = client.send_goal_async(SimulateSteps.Goal(steps=5))
rclpy.spin_until_future_complete(node, goal_future, timeout_sec=30.0)
handle = goal_future.result() if goal_future.done() else None
out["accepted"] = None if handle is None else bool(handle.accepted)
result_future = handle.get_result_async() if handle is not None and handle.accepted else None
print("asked", flush=True)
end = time.monotonic() + 60.0
while time.monotonic() < end and not select.select([sys.stdin], [], [], 0)[0]:
    rclpy.spin_once(node, timeout_sec=0.1)
out["result"] = result_future is not None and result_future.done()
print(json.dumps(out), flush=True)
