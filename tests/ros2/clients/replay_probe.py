"""Against `sigcore replay --until STEP` (paused there): wait for the simulation, collect /clock for 1.5 s, and
get the entity state of the robot named in argv[1] (simulation_interfaces)."""

import sys

from common import Client, emit
from rosgraph_msgs.msg import Clock
from simulation_interfaces.srv import GetEntityState

c = Client("replay_probe")
assert c.wait_ready(90.0), "the replayed simulation did not become ready"
clocks = c.listen(Clock, "/clock")
c.wait_for(lambda: bool(clocks), 20.0)
c.spin(1.5)
state = c.call(GetEntityState, "/get_entity_state", entity=sys.argv[1]).state.pose.position
emit({"clocks": [m.clock.sec * 1_000_000_000 + m.clock.nanosec for m in clocks],
      "position": [state.x, state.y, state.z]})
