"""Play, pause, step 10, reset and play through simulation_interfaces, one request at a time (each answered before
the next is sent): the results, in order."""

from common import Client, emit
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import ResetSimulation, SetSimulationState, StepSimulation

c = Client("run_control_probe")
c.wait_ready()


def set_state(state: int) -> int:
    return c.call(SetSimulationState, "/set_simulation_state", timeout=30.0, **{"state.state": state}).result.result


results = [
    set_state(SimulationState.STATE_PLAYING),
    set_state(SimulationState.STATE_PAUSED),
    c.call(StepSimulation, "/step_simulation", timeout=30.0, steps=10).result.result,
    c.call(ResetSimulation, "/reset_simulation", timeout=30.0).result.result,
    set_state(SimulationState.STATE_PLAYING),
]
emit({"results": results})
