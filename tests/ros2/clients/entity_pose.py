"""The pose of entity argv[1] from simulation_interfaces' get_entity_state: {"xyz": [...], "wxyz": [...]}."""

import sys

from common import Client, emit
from simulation_interfaces.srv import GetEntityState

c = Client("entity_pose")
c.wait_ready()
state = c.call(GetEntityState, "/get_entity_state", entity=sys.argv[1])
p, q = state.state.pose.position, state.state.pose.orientation
emit({"xyz": [p.x, p.y, p.z], "wxyz": [q.w, q.x, q.y, q.z]})
