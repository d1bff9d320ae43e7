"""Calls a service (argv[1], default /get_simulation_state; of type argv[2], ``pkg/srv/Name``, default
GetSimulationState) with a client whose response reader can never match the simulator's response writer
(transient-local durability asked, volatile offered), while its request writer does: the simulator's answer cannot
be delivered, for real. Once the service is in the ROS graph (at most 60 s: discovery is slow on a loaded machine),
sends a call every 0.5 s until a line comes on stdin (the test saw requests arrive: a request sent before the
server's request reader is matched is lost, and the graph can show the service before that) or 60 s passed; prints
whether any answer came (JSON)."""

from __future__ import annotations

import importlib
import json
import select
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from simulation_interfaces.srv import GetSimulationState

rclpy.init()
node = rclpy.create_node("unmatched_call")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
service = sys.argv[1] if len(sys.argv) > 1 else "/get_simulation_state"
kind: type = GetSimulationState
if len(sys.argv) > 2:
    package, _, name = sys.argv[2].split("/")
    kind = getattr(importlib.import_module(f"{package}.srv"), name)
client = node.create_client(kind, service, qos_profile=qos)
deadline = time.monotonic() + 60.0
while time.monotonic() < deadline and not any(name == service for name, _ in node.get_service_names_and_types()):
    rclpy.spin_once(node, timeout_sec=0.1)
rclpy.spin_once(node, timeout_sec=0.5)  # the request writer matches the reader the graph just showed
futures = []
end = time.monotonic() + 60.0
while time.monotonic() < end and not select.select([sys.stdin], [], [], 0)[0]:
    futures.append(client.call_async(kind.Request()))
    rclpy.spin_once(node, timeout_sec=0.5)
print(json.dumps({"answered": any(f.done() and f.result() is not None for f in futures), "sent": len(futures)}))
