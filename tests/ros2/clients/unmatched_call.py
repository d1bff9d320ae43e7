"""Calls /get_simulation_state with a client whose response reader can never match the simulator's response writer
(transient-local durability asked, volatile offered), while its request writer does: the simulator's answer cannot
be delivered, for real. Sends a call every 0.5 s for S seconds (argv[1]); prints whether any answer came (JSON)."""

from __future__ import annotations

import json
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from simulation_interfaces.srv import GetSimulationState

rclpy.init()
node = rclpy.create_node("unmatched_call")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
client = node.create_client(GetSimulationState, "/get_simulation_state", qos_profile=qos)
futures = []
end = time.monotonic() + float(sys.argv[1])
while time.monotonic() < end:
    futures.append(client.call_async(GetSimulationState.Request()))
    rclpy.spin_once(node, timeout_sec=0.5)
print(json.dumps({"answered": any(f.done() and f.result() is not None for f in futures), "sent": len(futures)}))
