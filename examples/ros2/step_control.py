"""simulation_interfaces: pause, step 100, simulate 500 steps as an action, reset, play; /clock follows."""

import time

import rclpy
from _ready import wait_ready
from rclpy.action import ActionClient
from rosgraph_msgs.msg import Clock
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import ResetSimulation, SetSimulationState, StepSimulation


def call(node, srv_type, name, request):
    client = node.create_client(srv_type, name)
    client.wait_for_service(timeout_sec=10.0)
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
    return future.result()


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("step_control")
    wait_ready(node)
    clock = {}
    node.create_subscription(Clock, "/clock", lambda m: clock.update(t=m.clock.sec + m.clock.nanosec * 1e-9), 10)

    def show(what: str) -> None:
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)
        print(f"{what:>20}: /clock = {clock.get('t', float('nan')):.3f} s")

    def set_state(state: int) -> None:
        req = SetSimulationState.Request()
        req.state.state = state
        print("set state", state, "->", call(node, SetSimulationState, "/set_simulation_state", req).result)

    set_state(SimulationState.STATE_PAUSED)
    show("paused")
    call(node, StepSimulation, "/step_simulation", StepSimulation.Request(steps=100))
    show("after 100 steps")
    action = ActionClient(node, SimulateSteps, "/simulate_steps")
    action.wait_for_server(timeout_sec=10.0)
    goal = action.send_goal_async(SimulateSteps.Goal(steps=500),
                                  feedback_callback=lambda f: print("  completed", f.feedback.completed_steps))
    rclpy.spin_until_future_complete(node, goal)
    result = goal.result().get_result_async()
    rclpy.spin_until_future_complete(node, result)
    show("after 500 more")
    call(node, ResetSimulation, "/reset_simulation", ResetSimulation.Request())
    show("after reset")  # poses are back to the world file's; time does not go back
    set_state(SimulationState.STATE_PLAYING)
    show("playing")
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
