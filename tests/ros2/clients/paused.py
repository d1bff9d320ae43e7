"""A simulation started with --paused: state PAUSED, /clock still, then it plays when asked."""

from common import Client, emit
from rosgraph_msgs.msg import Clock
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import GetSimulationState, SetSimulationState

c = Client("paused_probe")
c.wait_ready()
clocks = c.listen(Clock, "/clock")
c.wait_for(lambda: bool(clocks), 10.0)
c.spin(0.5)


def now():
    return clocks[-1].clock.sec + clocks[-1].clock.nanosec * 1e-9


state = c.call(GetSimulationState, "/get_simulation_state").state.state
still = now()
play = c.call(SetSimulationState, "/set_simulation_state",
              **{"state.state": SimulationState.STATE_PLAYING}).result.result
c.wait_for(lambda: now() > still + 0.1, 10.0)
emit({"state": state, "still": still, "played": now(), "play": play})
