"""A plain rclpy node that looks for the simulator: /sigcore/ready true (reliable, transient local, as a late joiner
must subscribe) and the simulator's ``/get_simulation_state`` service, then calls it (again after 1 s unanswered).

Usage: discover.py NAME LIMIT. Prints wall-clock times (``time.time()``, s) as JSON: ``init`` when its context and
node exist (its DDS participant is up), ``ready``, ``service`` (the server is discovered) and ``answered`` (a call
came back; made once both were seen), each None if it did not happen within LIMIT seconds of ``init``.
"""

from __future__ import annotations

import json
import os
import sys
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from simulation_interfaces.srv import GetSimulationState
from std_msgs.msg import Bool

name, limit = sys.argv[1], float(sys.argv[2])
rclpy.init()
node = rclpy.create_node(name)
executor = SingleThreadedExecutor()
executor.add_node(node)
times: dict[str, float | None] = {"init": time.time(), "ready": None, "service": None, "answered": None}
end = time.monotonic() + limit
CALL_TIMEOUT = 1.0  # s without an answer before the call is sent again
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


def _ready(msg: Bool) -> None:
    if msg.data and times["ready"] is None:
        times["ready"] = time.time()


node.create_subscription(Bool, "/sigcore/ready", _ready, latched)
client = node.create_client(GetSimulationState, "/get_simulation_state")
futures: list = []  # every call sent: an earlier one may be answered after a later one was sent
sent = 0.0
while time.monotonic() < end and times["answered"] is None:
    executor.spin_once(timeout_sec=0.02)
    if times["service"] is None and client.service_is_ready():
        times["service"] = time.time()
    if times["ready"] is None or times["service"] is None:
        continue
    # the documented order: /sigcore/ready, then the service, then a call with a timeout, sent again if unanswered
    # (a request written the moment a new server appears is lost if the server has not discovered the client's
    # request writer yet: DDS volatile semantics, not the simulator's)
    if any(f.done() and f.result() is not None for f in futures):
        times["answered"] = time.time()
    elif not futures or time.monotonic() - sent > CALL_TIMEOUT:
        futures.append(client.call_async(GetSimulationState.Request()))
        sent = time.monotonic()
sys.stdout.write(json.dumps({"name": name, **times}) + "\n")
sys.stdout.flush()
# the result is out: end now. Tearing down the node and the context is not what is measured, and once in CI (20 of
# these with the simulator on 2 loaded CPUs) a client that had printed its result hung in that teardown until killed
os._exit(0)
