"""The nodes' own services: parameters of /sigcore and /sigcore_actions answer; malformed SetParameters requests
are refused; afterwards the simulate_steps action still works."""

from common import Client, emit, todict
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import (
    DescribeParameters,
    GetParameters,
    GetParameterTypes,
    ListParameters,
    SetParameters,
    SetParametersAtomically,
)
from rclpy.action import ActionClient
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import GetSimulationState, SetSimulationState
from type_description_interfaces.srv import GetTypeDescription

c = Client("params_probe")
c.wait_ready()
out: dict = {}


def param(name: str, type_: int, **value: object) -> Parameter:
    return Parameter(name=name, value=ParameterValue(type=type_, **value))


def results(res: object) -> list | None:
    return None if res is None else [[r.successful, r.reason] for r in res.results]


for node in ("/sigcore", "/sigcore_actions"):
    got = {}
    res = c.call(ListParameters, f"{node}/list_parameters")
    got["list"] = None if res is None else list(res.result.names)
    res = c.call(GetParameters, f"{node}/get_parameters", names=["use_sim_time", "no_such_parameter"])
    got["get"] = None if res is None else todict(res.values)
    res = c.call(GetParameters, f"{node}/get_parameters", names=["use_sim_time"])
    got["use_sim_time"] = None if res is None else [[v.type, v.bool_value] for v in res.values]
    res = c.call(DescribeParameters, f"{node}/describe_parameters", names=["use_sim_time"])
    got["describe"] = None if res is None else [d.name for d in res.descriptors]
    res = c.call(GetParameterTypes, f"{node}/get_parameter_types", names=["use_sim_time"])
    got["types"] = None if res is None else list(res.types)
    res = c.call(GetTypeDescription, f"{node}/get_type_description", type_name="std_msgs/msg/Bool",
                 type_hash="RIHS01_0000", include_type_sources=False)
    got["type_description"] = None if res is None else [res.successful, res.failure_reason]
    # refusals: read-only, unknown, wrong type; then malformed (a type that does not exist, an empty name)
    got["set_use_sim_time"] = results(c.call(SetParameters, f"{node}/set_parameters", parameters=[
        param("use_sim_time", ParameterType.PARAMETER_BOOL, bool_value=False)]))
    got["set_unknown"] = results(c.call(SetParameters, f"{node}/set_parameters", parameters=[
        param("no_such_parameter", ParameterType.PARAMETER_INTEGER, integer_value=3)]))
    got["set_wrong_type"] = results(c.call(SetParameters, f"{node}/set_parameters", parameters=[
        param("use_sim_time", ParameterType.PARAMETER_STRING, string_value="yes")]))
    got["set_malformed"] = results(c.call(SetParameters, f"{node}/set_parameters", parameters=[
        param("use_sim_time", 200), param("", ParameterType.PARAMETER_BOOL, bool_value=True),
        param("x" * 100_000, 255)]))
    res = c.call(SetParametersAtomically, f"{node}/set_parameters_atomically", parameters=[
        param("use_sim_time", 77)])
    got["set_atomically_malformed"] = None if res is None else [res.result.successful, res.result.reason]
    res = c.call(GetParameters, f"{node}/get_parameters", names=["use_sim_time"])
    got["use_sim_time_after"] = None if res is None else [[v.type, v.bool_value] for v in res.values]
    out[node] = got

# the action node's executor must still serve: pause, then simulate 50 steps through the action
out["pause"] = c.call(SetSimulationState, "/set_simulation_state",
                      **{"state.state": SimulationState.STATE_PAUSED}).result.result
action = ActionClient(c.node, SimulateSteps, "/simulate_steps")
out["action_server"] = action.wait_for_server(timeout_sec=10)
c.spin(0.5)
goal_future = action.send_goal_async(SimulateSteps.Goal(steps=50))
c.executor.spin_until_future_complete(goal_future, timeout_sec=10)
goal = goal_future.result()
out["accepted"] = goal is not None and goal.accepted
if out["accepted"]:
    result_future = goal.get_result_async()
    c.executor.spin_until_future_complete(result_future, timeout_sec=30)
    out["action"] = result_future.result().result.result.result if result_future.done() else None
out["state"] = c.call(GetSimulationState, "/get_simulation_state").state.state
emit(out)
