"""simulate_steps goals that run long (the simulation paused at real-time pace): MAX goals run, one more is
rejected, and meanwhile the action's get_result (an unknown goal), the node's parameter services and a cancel are
answered within the client's timeout. Prints the outcome as JSON."""

import sys
import time
import uuid

from common import Client, emit
from rcl_interfaces.srv import ListParameters
from rclpy.action import ActionClient
from simulation_interfaces.action import SimulateSteps

running = int(sys.argv[1])  # goals to start (MAX_RUNNING), each long
c = Client("busy_actions")
c.wait_ready()
action = ActionClient(c.node, SimulateSteps, "/simulate_steps")
action.wait_for_server(timeout_sec=10)
c.spin(1.0)
out: dict = {"accepted": 0}
goals = []
for _ in range(running + 1):
    future = action.send_goal_async(SimulateSteps.Goal(steps=1_000_000))
    c.executor.spin_until_future_complete(future, timeout_sec=10)
    handle = future.result() if future.done() else None
    out["accepted"] += bool(handle is not None and handle.accepted)
    if handle is not None and handle.accepted:
        goals.append(handle)
out["last_answered"] = handle is not None
out["last_accepted"] = bool(handle is not None and handle.accepted)
# while the accepted goals run: the action's result service answers for an unknown goal
t0 = time.monotonic()
unknown = c.call(SimulateSteps.Impl.GetResultService, "/simulate_steps/_action/get_result", timeout=10.0,
                 **{"goal_id.uuid": list(uuid.uuid4().bytes)})
out["unknown_result_s"] = time.monotonic() - t0
out["unknown_status"] = None if unknown is None else unknown.status
t0 = time.monotonic()
params = c.call(ListParameters, "/sigcore_actions/list_parameters", timeout=10.0)
out["parameters_s"] = time.monotonic() - t0
out["parameters_answered"] = params is not None
# cancel them all: each ends, and a new goal is accepted again
canceled = 0
for handle in goals:
    future = handle.cancel_goal_async()
    c.executor.spin_until_future_complete(future, timeout_sec=10)
    canceled += bool(future.done() and future.result().goals_canceling)
out["canceled"] = canceled
results = [g.get_result_async() for g in goals]
c.wait_for(lambda: all(r.done() for r in results), 20.0)
out["ended"] = sum(r.done() for r in results)
future = action.send_goal_async(SimulateSteps.Goal(steps=5))
c.executor.spin_until_future_complete(future, timeout_sec=10)
after = future.result() if future.done() else None
out["accepted_after"] = bool(after is not None and after.accepted)
if after is not None and after.accepted:
    result = after.get_result_async()
    c.executor.spin_until_future_complete(result, timeout_sec=20)
    out["after_result"] = result.result().result.result.result if result.done() else None
emit(out)
