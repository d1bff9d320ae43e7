"""The default selection (sigros_agents=auto) seen from another process: the graph, the shared per-name endpoints
answering for plain objects (cube, ball), and the refusals of a missing or wrong name."""

import sys
import time

from common import Client, emit, todict
from sigcore_msgs import msg, srv
from simulation_interfaces.srv import GetEntityState

c = Client("shared_probe")
c.wait_ready()
expected = int(sys.argv[1])
end = time.monotonic() + 30
graph: set[str] = set()
while time.monotonic() < end:  # discovery of every endpoint takes a moment
    c.spin(0.5)
    graph = c.graph()
    if len(graph) >= expected:
        break
out = {"graph": sorted(graph)}
out["cube"] = todict(c.call(srv.GetObjPosition, "/sigcore/sigros/get_obj_position", name="cube"))
out["cube_truth"] = todict(c.call(GetEntityState, "/get_entity_state", entity="cube").state.pose.position)
out["cube_mass"] = todict(c.call(srv.GetMass, "/sigcore/sigros/get_mass", name="cube"))
out["no_name"] = todict(c.call(srv.GetObjPosition, "/sigcore/sigros/get_obj_position", name=""))
out["unknown"] = todict(c.call(srv.GetObjPosition, "/sigcore/sigros/get_obj_position", name="nobody"))
c.publish(msg.EntityVector, "/sigcore/sigros/setPosition", name="ball", x=0.5, y=-1.5, z=0.05)


def ball() -> dict:
    return todict(c.call(srv.GetObjPosition, "/sigcore/sigros/get_obj_position", name="ball"))


c.wait_for(lambda: abs(ball()["pos_x"] - 0.5) < 1e-3, 10.0)
out["ball"] = ball()
emit(out)
