"""Play, pause, step 10, reset and play through simulation_interfaces, one request at a time: each is sent once the
previous one is answered and the test has said "go" on standard input (it has taken that verb's loop passes, so two
requests never arrive in one servicing of the transport): the results, in order."""

import sys
from collections.abc import Callable

from common import Client, emit
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import ResetSimulation, SetSimulationState, StepSimulation

c = Client("run_control_probe")
c.wait_ready()


def set_state(state: int) -> int:
    return c.call(SetSimulationState, "/set_simulation_state", timeout=30.0, **{"state.state": state}).result.result


def after_go(request: Callable[[], int]) -> Callable[[], int]:
    def send() -> int:
        if not sys.stdin.readline():
            raise SystemExit("the test closed standard input before saying go")
        return request()
    return send


requests = [
    lambda: set_state(SimulationState.STATE_PLAYING),
    after_go(lambda: set_state(SimulationState.STATE_PAUSED)),
    after_go(lambda: c.call(StepSimulation, "/step_simulation", timeout=30.0, steps=10).result.result),
    after_go(lambda: c.call(ResetSimulation, "/reset_simulation", timeout=30.0).result.result),
    after_go(lambda: set_state(SimulationState.STATE_PLAYING)),
]
emit({"results": [request() for request in requests]})
